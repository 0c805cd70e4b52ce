// Shared by the training tests: a small procedural scene made once per test process, and fresh run folders.
#pragma once

#include <string>

#include "support/temp_scene.hpp"

namespace mipnerf::test {

// A 32×32 procedural scene (16 train views, 2 val, 2 test, 2 scales) in a temporary folder.
inline const std::string& small_scene() {
  static const std::string path = write_temp_scene("train-scene", {32, 16, 2, 2, 4});
  return path;
}

inline std::string fresh_run_dir(const std::string& name) { return fresh_temp_dir("run-" + name).string(); }

}  // namespace mipnerf::test
