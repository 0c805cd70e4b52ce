// Temporary folders and procedural scenes for tests: one set per test process (the pid is in every name), so
// CTest can run test executables side by side.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <string>

#include "data/synthetic/procedural.hpp"

namespace mipnerf::test {

// <system temp>/mipnerf-<name>-<pid>; not created.
inline std::filesystem::path temp_path(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("mipnerf-" + name + "-" + std::to_string(::getpid()));
}

// temp_path(name), removed first so that every run starts empty.
inline std::filesystem::path fresh_temp_dir(const std::string& name) {
  const auto dir = temp_path(name);
  std::filesystem::remove_all(dir);
  return dir;
}

// The sizes a test's scene needs; the rest of data::SceneOptions keeps its defaults (seed 0, Blender's field of
// view). Two render threads: the test machines have two cores.
struct TestSceneSize {
  uint32_t size_px;
  uint32_t train_views;
  uint32_t held_out_views;  // val and test views each
  int scales;               // > 1 also writes OUT/multiscale
  uint32_t samples_per_axis;
};

// Writes a procedural scene into fresh_temp_dir(name) and returns its path.
inline std::string write_temp_scene(const std::string& name, const TestSceneSize& size) {
  const auto dir = fresh_temp_dir(name);
  data::SceneOptions options;
  options.size_px = size.size_px;
  options.train_views = size.train_views;
  options.val_views = size.held_out_views;
  options.test_views = size.held_out_views;
  options.scales = size.scales;
  options.samples_per_axis = size.samples_per_axis;
  options.threads = 2;
  data::write_procedural_scene(dir.string(), options);
  return dir.string();
}

}  // namespace mipnerf::test
