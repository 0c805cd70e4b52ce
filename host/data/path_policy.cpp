// The dataset path policy: relative paths that stay inside their folder.
#include "data/path_policy.hpp"

#include <atomic>
#include <filesystem>

#include "core/error.hpp"

namespace mipnerf::data {
namespace fs = std::filesystem;
namespace {

std::atomic<bool>& allowed() {
  static std::atomic<bool> value{false};
  return value;
}

// Lexically: absolute ("/x", "C:x"), or a first component ".." once "a/../b" parts are folded.
bool climbs_out(const std::string& relative) {
  const fs::path path(relative);
  if (path.has_root_path()) return true;
  const fs::path normal = path.lexically_normal();
  return !normal.empty() && *normal.begin() == "..";
}

}  // namespace

void set_outside_paths_allowed(bool value) { allowed().store(value); }

bool outside_paths_allowed() { return allowed().load(); }

void check_inside_folder(const std::string& base, const std::string& relative, const std::string& where,
                         const std::string& what) {
  if (outside_paths_allowed() || !climbs_out(relative)) return;
  throw Error(where + ": " + what + " '" + relative + "' lies outside " + (base.empty() ? "." : base) +
              ": a dataset names only files in its own folder; move the images there, or pass "
              "mipnerf-cl --allow-outside-paths if you trust this file");
}

}  // namespace mipnerf::data
