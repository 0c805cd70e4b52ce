// Hints for paths that do not exist (io/path_hint): the entry meant where one is close and the path through it
// exists, the missing folder named where none is.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>

#include "io/path_hint.hpp"
#include "support/data_fixtures.hpp"

using namespace mipnerf;
namespace fs = std::filesystem;

TEST_CASE("path hint: a close name beside the missing part, when the path through it exists") {
  test::TempDir dir;
  fs::create_directories(dir / "llff/flower/images_8");
  std::ofstream(dir / "llff/flower/poses_bounds.npy") << "x";
  CHECK(io::missing_path_hint(dir / "llff/flwer") == "did you mean '" + dir / "llff/flower" + "'?");
  // A folder above the last part: the rest of the path must exist through the name meant.
  CHECK(io::missing_path_hint(dir / "lllf/flower/images_8") == "did you mean '" + dir / "llff/flower/images_8" + "'?");
  CHECK(io::missing_path_hint(dir / "llff/flower/poses_bound.npy") ==
        "did you mean '" + dir / "llff/flower/poses_bounds.npy" + "'?");
  // The folder meant is there, but not what follows it: name the folder that is missing instead.
  CHECK(io::missing_path_hint(dir / "lllf/tulip") == "no 'lllf' in " + dir.path());
  // Nothing close.
  CHECK(io::missing_path_hint(dir / "llff/zzzzzz") == "");
  CHECK(io::missing_path_hint(dir / "nowhere/flower") == "no 'nowhere' in " + dir.path());
  // A path that exists needs no hint, with or without a trailing separator.
  CHECK(io::missing_path_hint(dir / "llff/flower") == "");
  CHECK(io::missing_path_hint(dir / "llff/flower/") == "");
}

TEST_CASE("path hint: every close name whose path exists is named") {
  test::TempDir dir;
  fs::create_directories(dir / "scene_a");
  fs::create_directories(dir / "scene_b");
  CHECK(io::missing_path_hint(dir / "scene_c") ==
        "did you mean '" + dir / "scene_a" + "' or '" + dir / "scene_b" + "'?");
}
