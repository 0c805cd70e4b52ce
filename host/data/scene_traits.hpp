// What a dataset is, read from its metadata and first image without loading it: the facts that decide which
// effects a scene calls for (train/scene_effects.hpp turns them into settings).
#pragma once

#include <string>

#include "data/dataset.hpp"

namespace mipnerf::data {

struct SceneTraits {
  DatasetFormat format = DatasetFormat::blender;
  bool has_alpha = false;    // the first image has an alpha channel (rendered objects, not photos)
  bool llff_360 = false;     // an LLFF capture looking inward from all around (data::looks_360), not forward
  bool multiscale = false;   // images at several scales on disk (multiscale Blender)
};

// Throws mipnerf::Error naming the file when the dataset's metadata or first image cannot be read.
SceneTraits scene_traits(const std::string& path, const LoadOptions& options);

}  // namespace mipnerf::data
