// Shared by the training tests: a small procedural scene made once per test process, and fresh run folders.
#pragma once

#include <filesystem>
#include <string>

#include <unistd.h>

#include "data/procedural.hpp"

namespace mipnerf::test {

// A 32×32 procedural scene (16 train views, 2 val, 2 test, 2 scales) in a temporary folder.
inline const std::string& small_scene() {
  static const std::string path = [] {
    const auto dir = std::filesystem::temp_directory_path() / ("mipnerf-train-scene-" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    data::SceneOptions options;
    options.size_px = 32;
    options.train_views = 16;
    options.val_views = 2;
    options.test_views = 2;
    options.scales = 2;
    options.samples_per_axis = 4;
    options.threads = 2;
    data::write_procedural_scene(dir.string(), options);
    return dir.string();
  }();
  return path;
}

inline std::string fresh_run_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("mipnerf-run-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  return dir.string();
}

}  // namespace mipnerf::test
