// A dataset names only files inside its own folder (data/path_policy.hpp): a file_path that is absolute or climbs
// out with `..` is refused with one line naming the file, the frame and the path, in every format that lists paths
// (Blender, transforms.json and multiscale metadata here; a COLMAP model's image names in test_colmap.cpp), unless the
// process allows it; paths that stay inside after `a/../b` folding, and links inside the folder, are the folder's own.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>

#include "data/dataset.hpp"
#include "data/import/colmap_import.hpp"
#include "data/path_policy.hpp"
#include "io/png.hpp"
#include "support/data_fixtures.hpp"

using namespace mipnerf;
using test::contains;
using test::error_of;
namespace fs = std::filesystem;

namespace {

// DIR/set/: a transforms.json of two frames; DIR/outside.png and DIR/set/images/0.png are both real images.
struct EscapeSet {
  test::TempDir dir;
  fs::path set = fs::path(dir.path()) / "set";
  EscapeSet() {
    const auto rgba = test::test_rgba8(0, 4, 4);
    fs::create_directories(set / "images");
    io::write_png8((fs::path(dir.path()) / "outside.png").string(), 4, 4, 4, rgba.data());
    io::write_png8((set / "images/0.png").string(), 4, 4, 4, rgba.data());
  }
  std::string load_error(const std::string& second_path) const {
    io::Json frames = io::Json::array();
    for (const std::string& path : {std::string("images/0.png"), second_path}) {
      frames.push_back({{"file_path", path}, {"transform_matrix", data::pose_to_json(test::test_pose(0))}});
    }
    io::write_json((set / "transforms.json").string(),
                   {{"fl_x", 5}, {"fl_y", 5}, {"cx", 2}, {"cy", 2}, {"w", 4}, {"h", 4}, {"frames", frames}});
    return error_of([&] { data::load_dataset((set / "transforms.json").string()); });
  }
};

struct AllowedInScope {
  AllowedInScope() { data::set_outside_paths_allowed(true); }
  ~AllowedInScope() { data::set_outside_paths_allowed(false); }
};

}  // namespace

TEST_CASE("path policy: a transforms.json naming a file outside its folder is refused, one line naming it") {
  EscapeSet s;
  const std::string outside = (fs::path(s.dir.path()) / "outside.png").string();
  for (const std::string& path : {std::string("../outside.png"), std::string("images/../../outside.png"), outside,
                                  std::string("./../outside.png")}) {
    CAPTURE(path);
    const std::string message = s.load_error(path);
    CHECK(contains(message, (s.set / "transforms.json").string() + ": frames[1]: file_path '" + path +
                                "' lies outside " + s.set.string() + ": a dataset names only files in its own folder"));
    CHECK(contains(message, "--allow-outside-paths"));
    CHECK(message.find('\n') == std::string::npos);
  }
  // Paths that stay inside once folded, and a link inside the folder that points out of it (the folder's own).
  CHECK(s.load_error("images/../images/0.png").empty());
  CHECK(s.load_error("./images/0.png").empty());
  fs::create_symlink(fs::path(s.dir.path()) / "outside.png", s.set / "linked.png");
  CHECK(s.load_error("linked.png").empty());
}

TEST_CASE("path policy: --allow-outside-paths lets such a file load") {
  EscapeSet s;
  const AllowedInScope allowed;
  CHECK(s.load_error("../outside.png").empty());
  CHECK(s.load_error((fs::path(s.dir.path()) / "outside.png").string()).empty());
}

TEST_CASE("path policy: a Blender split naming a file outside its folder is refused") {
  test::TempDir dir;
  test::write_blender_split((fs::path(dir.path()) / "set").string(), "train", 2, 4, 4);
  const fs::path json = fs::path(dir.path()) / "set/transforms_train.json";
  io::Json j = io::read_json(json.string());
  j["frames"][1]["file_path"] = "../set/train/r_1";
  io::write_json(json.string(), j);
  CHECK(contains(error_of([&] { data::load_dataset((fs::path(dir.path()) / "set").string()); }),
                 "file_path '../set/train/r_1' lies outside"));
}
