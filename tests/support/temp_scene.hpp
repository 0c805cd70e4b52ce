// Temporary folders and procedural scenes for tests: one set per test process (the pid is in every name), so
// CTest can run test executables side by side.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "data/synthetic/procedural.hpp"

namespace mipnerf::test {

// <system temp>/mipnerf-<name>-<pid>; not created.
inline std::filesystem::path temp_path(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("mipnerf-" + name + "-" + std::to_string(::getpid()));
}

// This process's entries of the system temp folder: every "mipnerf-<name>-<pid>" (temp_path's names, and the tests'
// own of the same pattern). The pid ends the name after a '-', so another process's pid that ends in ours does not
// match.
inline std::vector<std::filesystem::path> process_temp_entries() {
  const std::string suffix = "-" + std::to_string(::getpid());
  std::vector<std::filesystem::path> entries;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::temp_directory_path(), error)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("mipnerf-", 0) == 0 && name.size() > suffix.size() &&
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0) {
      entries.push_back(entry.path());
    }
  }
  return entries;
}

// Removes process_temp_entries(): the test mains call it after a run that passed, so the suite does not leave its
// scenes and runs behind (a whole test command left ~300 MB of them in /tmp until 2026-12-03); a failed run keeps
// them for a look, and the main names them.
inline void remove_process_temp_entries() {
  for (const auto& entry : process_temp_entries()) {
    std::error_code ignored;  // a folder another thread still writes into is left; the sweep is tidiness, not a check
    std::filesystem::remove_all(entry, ignored);
  }
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
