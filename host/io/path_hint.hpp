// What to tell someone whose path does not exist: the first of its parts that is missing, and the entry beside it
// closest in spelling when the path with that entry in its place exists ("did you mean 'data/llff/flower'?").
#pragma once

#include <string>

namespace mipnerf::io {

// "did you mean 'Q'?" (or "'Q' or 'R'") when `path` does not exist but changing its first missing part to a close
// name in that folder (core/suggest.hpp) gives paths that do; else "no 'X' in D" when the missing part is a folder
// above the last one; else "" (the path exists, its last part has no close sibling, or its folder cannot be read).
std::string missing_path_hint(const std::string& path);

}  // namespace mipnerf::io
