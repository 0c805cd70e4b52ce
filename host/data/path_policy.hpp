// Which files a dataset may name. A transforms.json, a multiscale metadata.json or a COLMAP model lists its images by
// path; a file downloaded with a dataset could name `../../somewhere/x.png` or `/home/you/secret.png`, and training
// would read it. Every such path must stay inside the folder that names it (lexically: not absolute, and no `..` that
// climbs out of it; links inside the folder are the folder's own business, as `import-colmap` makes them), unless the
// user allows otherwise for the process (`mipnerf-cl --allow-outside-paths`).
#pragma once

#include <string>

namespace mipnerf::data {

void set_outside_paths_allowed(bool allowed);
bool outside_paths_allowed();

// Throws mipnerf::Error "<where>: <what> '<relative>' lies outside <base>: …" when `relative` (as the file gives it,
// to be joined to `base`) is absolute or climbs out of `base`, and outside paths are not allowed.
void check_inside_folder(const std::string& base, const std::string& relative, const std::string& where,
                         const std::string& what);

}  // namespace mipnerf::data
