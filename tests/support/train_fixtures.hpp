// Shared by the training tests: a small procedural scene made once per test process, and fresh run folders.
#pragma once

#include <filesystem>
#include <string>

#include "support/temp_scene.hpp"

namespace mipnerf::test {

// A 32×32 procedural scene (16 train views, 2 val, 2 test, 2 scales) in a temporary folder.
inline const std::string& small_scene() {
  static const std::string path = write_temp_scene("train-scene", {32, 16, 2, 2, 4});
  return path;
}

// An empty folder of its own (made, so that logs of child processes can be written into it at once).
inline std::string fresh_run_dir(const std::string& name) {
  const auto dir = fresh_temp_dir("run-" + name);
  std::filesystem::create_directories(dir);
  return dir.string();
}

}  // namespace mipnerf::test
