// Every kind of bad input gives a one-line mipnerf::Error that names the file and says what is wrong:
// missing files, malformed JSON, missing keys, images of differing size, non-finite or non-rigid poses,
// unreadable PNGs, lens distortion, other image types, inconsistent intrinsics and near/far.
#include <doctest/doctest.h>

#include <fstream>

#include "data/dataset.hpp"
#include "data/multiscale.hpp"
#include "data/pose.hpp"
#include "support/data_fixtures.hpp"

using namespace mipnerf;
using test::contains;
using test::error_of;

namespace {

// A valid 2-frame Blender split in a fresh folder; `edit` changes its transforms JSON before loading.
struct BrokenSet {
  test::TempDir dir;
  BrokenSet() { test::write_blender_split(dir.path(), "train", 2, 4, 4); }
  std::string json_path() const { return dir / "transforms_train.json"; }
  io::Json json() const { return io::read_json(json_path()); }
  void write(const io::Json& value) const { io::write_json(json_path(), value); }
  void write_text(const std::string& text) const { std::ofstream(json_path()) << text; }
  // The error of loading the folder; checks it is one line.
  std::string load_error() const {
    const std::string message = error_of([this] { data::load_dataset(dir.path()); });
    CHECK(message.find('\n') == std::string::npos);
    return message;
  }
};

}  // namespace

TEST_CASE("errors: missing folder, folder without a dataset, missing image") {
  BrokenSet set;
  CHECK(error_of([&] { data::load_dataset(set.dir / "nowhere"); }) == set.dir / "nowhere: no such file or folder");
  std::filesystem::create_directories(set.dir / "other/notes");
  CHECK(error_of([&] { data::load_dataset(set.dir / "other"); }) ==
        set.dir / ("other: no dataset here: expected transforms_train.json (Blender), metadata.json (multiscale "
                   "Blender), transforms.json or poses_bounds.npy with images/ (an LLFF capture); for photos without "
                   "poses, see `mipnerf-cl dataset from-photos`"));
  std::filesystem::remove(set.dir / "train/r_1.png");
  CHECK(set.load_error() == set.dir / "train/r_1.png: no such file (listed by " + set.json_path() + ": frames[1])");
}

TEST_CASE("errors: malformed JSON and numbers that overflow give the file and the position") {
  BrokenSet set;
  set.write_text("{\"camera_angle_x\": 0.69,\n \"frames\": [}\n");
  CHECK(contains(set.load_error(), set.json_path() + ": malformed JSON at line 2, column 13: syntax error"));
  set.write_text("{\"camera_angle_x\": 0.69,\n \"frames\": [{\"file_path\": \"./train/r_0\", \"transform_matrix\": "
                 "[[NaN, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}]}");
  CHECK(contains(set.load_error(), "malformed JSON at line 2, column 64"));
  CHECK(contains(set.load_error(), "non-finite"));
  set.write_text("{\"camera_angle_x\": 0.69,\n \"frames\": [{\"file_path\": \"./train/r_0\", \"transform_matrix\": "
                 "[[1e999, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}]}");
  CHECK(contains(set.load_error(), set.json_path() + ": malformed JSON at line 2, column 64: number overflow"));
  CHECK(contains(set.load_error(), "not finite"));
}

TEST_CASE("errors: missing keys name the key and the frame") {
  BrokenSet set;
  auto json = set.json();
  json["frames"][1].erase("transform_matrix");
  set.write(json);
  CHECK(set.load_error() == set.json_path() + ": frames[1]: missing key 'transform_matrix'");
  json = set.json();
  json.erase("frames");
  set.write(json);
  CHECK(set.load_error() == set.json_path() + ": missing key 'frames'");
  set.write({{"camera_angle_x", 0.7}, {"frames", {{{"transform_matrix", data::pose_to_json(test::test_pose(0))}}}}});
  CHECK(set.load_error() == set.json_path() + ": frames[0]: missing key 'file_path'");
  set.write({{"frames", {{{"file_path", "./train/r_0"}, {"transform_matrix", data::pose_to_json(test::test_pose(0))}}}}});
  CHECK(set.load_error() == set.json_path() + ": frames[0]: no focal length: give 'fl_x' (pixels) or "
                                              "'camera_angle_x' (radians)");
  set.write({{"camera_angle_x", "wide"}, {"frames", io::Json::array()}});
  CHECK(set.load_error() == set.json_path() + ": 'camera_angle_x' must be a number, got string");
}

TEST_CASE("errors: images of differing size in a Blender split") {
  BrokenSet set;
  const auto rgba = test::test_rgba8(0, 6, 4);
  io::write_png8(set.dir / "train/r_1.png", 6, 4, 4, rgba.data());
  CHECK(set.load_error() == set.dir / "train/r_1.png: the image is 6x4 but " + set.dir / "train/r_0.png is 4x4; "
                                      "every image of a Blender split must have the same size (resize or re-render it)");
}

TEST_CASE("errors: non-rigid, mirrored, malformed and non-finite poses") {
  BrokenSet set;
  auto json = set.json();
  // Scaled by 1.01: |RᵀR − I| = 0.0201.
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) json["frames"][1]["transform_matrix"][r][c] = json["frames"][1]["transform_matrix"][r][c].get<double>() * 1.01;
  set.write(json);
  CHECK(contains(set.load_error(), set.json_path() + ": frames[1]: the pose's rotation is not orthonormal (max "
                                                     "|R^T R - I| = 0.0201, tolerance 0.001)"));
  json = set.json();
  for (int r = 0; r < 3; ++r) json["frames"][0]["transform_matrix"][r][0] = -json["frames"][0]["transform_matrix"][r][0].get<double>();
  set.write(json);
  CHECK(contains(set.load_error(), set.json_path() + ": frames[0]: the pose's rotation has determinant -1 instead "
                                                     "of +1: it is a reflection"));
  json = set.json();
  json["frames"][0]["transform_matrix"][3][0] = 0.5;
  set.write(json);
  CHECK(contains(set.load_error(), "frames[0]: the pose's last row must be 0 0 0 1"));
  // A wrong last row whose later entry is not a number: the message quoted the row before checking it, and the
  // JSON library's type error escaped (found by fuzz: blender).
  json["frames"][0]["transform_matrix"][3][3] = "h";
  set.write(json);
  CHECK(contains(set.load_error(), "frames[0]: the pose must be a 4x4 (or 3x4) array of rows of numbers (row 3 "
                                   "holds a string)"));
  json = set.json();
  json["frames"][0]["transform_matrix"] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  set.write(json);
  CHECK(contains(set.load_error(), "frames[0]: the pose must be a 4x4 (or 3x4) array of rows of numbers"));
  json["frames"][0]["transform_matrix"] = {{1, 0, 0, "x"}, {0, 1, 0, 0}, {0, 0, 1, 0}};
  set.write(json);
  CHECK(contains(set.load_error(), "(row 0 holds a string)"));
  // A pose built in memory (not through JSON, which cannot hold NaN) is checked for finiteness too.
  data::Matrix34 nan_pose = test::test_pose(0);
  nan_pose[7] = std::nan("");
  CHECK(error_of([&] { data::check_rigid_pose(nan_pose, "mem"); }) ==
        "mem: the pose has a non-finite entry; fix or drop this frame");
  // The tolerance accepts float32-rounded rotations (Blender's files).
  data::Matrix34 rounded = test::test_pose(2);
  for (double& v : rounded) v = static_cast<float>(v);
  CHECK(error_of([&] { data::check_rigid_pose(rounded, "ok"); }).empty());
}

TEST_CASE("errors: unreadable PNGs and other image types") {
  BrokenSet set;
  { std::ofstream(set.dir / "train/r_1.png") << "GIF89a not a png"; }
  CHECK(set.load_error() == set.dir / "train/r_1.png: unreadable PNG (not a PNG file: the signature is missing); "
                                      "re-export it as an 8- or 16-bit PNG");
  const auto rgba = test::test_rgba8(0, 4, 4);
  auto bytes = io::encode_png8(4, 4, 4, rgba.data());
  bytes.resize(bytes.size() - 20);  // cut inside the image data / end chunk
  {
    std::ofstream out(set.dir / "train/r_1.png", std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  }
  CHECK(contains(set.load_error(), set.dir / "train/r_1.png: unreadable PNG ("));
  auto json = set.json();
  json["frames"][1]["file_path"] = "./train/photo.jpg";
  { std::ofstream(set.dir / "train/photo.jpg") << "jpeg"; }
  set.write(json);
  CHECK(set.load_error() == set.dir / "train/photo.jpg: not a JPEG file (no FF D8 FF start marker)");
  json["frames"][1]["file_path"] = "./train/photo.webp";
  { std::ofstream(set.dir / "train/photo.webp") << "webp"; }
  set.write(json);
  CHECK(set.load_error() == set.dir / "train/photo.webp: only PNG and JPEG images are supported (" + set.json_path() +
                                      ": frames[1]); convert the images to PNG and update file_path");
}

TEST_CASE("errors: transforms.json lens models, inconsistent w/h, near/far") {
  BrokenSet set;
  const auto frames = set.json()["frames"];
  const std::string file = set.dir / "transforms.json";
  auto load = [&](const io::Json& root) {
    io::write_json(file, root);
    return error_of([&] { data::load_dataset(file); });
  };
  // A lens mipnerf-cl reads loads (its rays go through the lens); the rest are one-line errors naming the camera.
  CHECK(load({{"fl_x", 5.0}, {"k1", -0.05}, {"frames", frames}}).empty());
  CHECK(load({{"fl_x", 5.0}, {"camera_model", "OPENCV_FISHEYE"}, {"k1", 0.01}, {"frames", frames}}).empty());
  CHECK(load({{"fl_x", 5.0}, {"camera_model", "FULL_OPENCV"}, {"k1", -0.05}, {"k5", 0.01}, {"frames", frames}}).empty());
  // Coefficients without a model are OPENCV's (instant-ngp), which has no k5.
  CHECK(load({{"fl_x", 5.0}, {"k1", -0.05}, {"k5", 0.01}, {"frames", frames}}) ==
        file + ": camera_model OPENCV has coefficients it does not take (SIMPLE_RADIAL: k1; RADIAL: k1, k2; OPENCV: "
               "k1, k2, p1, p2; OPENCV_FISHEYE: k1, k2, k3, k4; FULL_OPENCV: k1, k2, p1, p2, k3, k4, k5, k6)");
  auto with_frame_model = io::Json{{"fl_x", 5.0}, {"frames", frames}};
  with_frame_model["frames"][1]["camera_model"] = "FOV";
  CHECK(load(with_frame_model) ==
        file + ": frames[1]: camera_model 'FOV' is not read: mipnerf-cl reads SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, "
               "RADIAL, OPENCV, OPENCV_FISHEYE and FULL_OPENCV cameras; undistort the images to a pinhole camera first (e.g. COLMAP's "
               "image_undistorter)");
  CHECK(load({{"fl_x", 5.0}, {"camera_model", "SIMPLE_RADIAL"}, {"k1", 0.1}, {"p1", 0.01}, {"frames", frames}}) ==
        file + ": camera_model SIMPLE_RADIAL has coefficients it does not take (SIMPLE_RADIAL: k1; RADIAL: k1, k2; "
               "OPENCV: k1, k2, p1, p2; OPENCV_FISHEYE: k1, k2, k3, k4; FULL_OPENCV: k1, k2, p1, p2, k3, k4, k5, k6)");
  CHECK(contains(load({{"fl_x", 5.0}, {"k1", "strong"}, {"frames", frames}}), file + ": 'k1'"));
  // k1 = −2 folds the image at r = 1/√6 = 0.41 (normalised): the 4×4 image at focal 2 px reaches r = 1.06.
  CHECK(load({{"fl_x", 2.0}, {"camera_model", "SIMPLE_RADIAL"}, {"k1", -2.0}, {"frames", frames}}) ==
        file + ": frames[1]: its SIMPLE_RADIAL lens cannot be inverted at pixel (0, 0): no ray leaves the lens there "
               "(the distortion folds the image, or the pixel lies beyond the lens's field); check the coefficients (a "
               "lens COLMAP estimates is invertible over its image)");
  // Frame 0 is held out for "test", so frames[1] (the first of "train") is read first.
  CHECK(load({{"fl_x", 5.0}, {"w", 8}, {"h", 4}, {"frames", frames}}) ==
        file + ": frames[1]: the image is 4x4 but w/h say 8x4; the intrinsics must describe the image as stored "
               "(rescale fl_x, fl_y, cx, cy with it)");
  CHECK(load({{"fl_x", -5.0}, {"frames", frames}}) == file + ": 'fl_x' must be positive, got -5.000000");
  CHECK(load({{"fl_x", 5.0}, {"near", 3.0}, {"far", 3.0}, {"frames", frames}}) ==
        file + ": frames[0]: near = 3.000000, far = 3.000000: need 0 <= near < far");
  CHECK(load({{"fl_x", 5.0}, {"frames", io::Json::array()}}) == file + ": 'frames' is empty: the split has no images");
}

TEST_CASE("errors: multiscale metadata.json with inconsistent columns") {
  BrokenSet set;
  data::write_multiscale(set.dir.path(), set.dir / "ms", 2);
  auto meta = io::read_json(set.dir / "ms/metadata.json");
  meta["train"]["lossmult"].erase(meta["train"]["lossmult"].size() - 1);
  io::write_json(set.dir / "ms/metadata.json", meta);
  CHECK(error_of([&] { data::load_dataset(set.dir / "ms"); }) ==
        set.dir / "ms/metadata.json: train: 'lossmult' has 3 entries but 'file_path' has 4");
}

// Each kind of path that holds no dataset gets the hint that fits it, in one line: the name meant, the command that
// makes a dataset of what is there, or the subfolder that holds one.
TEST_CASE("errors: a path without a dataset says what to do with what is there") {
  BrokenSet set;
  const std::string d = set.dir.path();
  const auto load_error = [](const std::string& path) {
    const std::string message = error_of([&] { data::load_dataset(path); });
    CHECK(message.find('\n') == std::string::npos);
    return message;
  };
  const auto touch = [](const std::string& path) {
    std::filesystem::create_directories(std::filesystem::path(path).parent_path());
    std::ofstream(path) << "not decoded here";
  };
  // A slip in the name: the sibling meant, when the path through it exists; else the folder that is missing.
  test::write_blender_split(d + "/scenes/flower", "train", 2, 4, 4);
  const std::string flower = d + "/scenes/flower";
  CHECK(load_error(d + "/scenes/flwer") == d + "/scenes/flwer: no such file or folder; did you mean '" + flower + "'?");
  CHECK(load_error(d + "/scnes/flower") == d + "/scnes/flower: no such file or folder; did you mean '" + flower + "'?");
  CHECK(load_error(d + "/nowhere/flower") == d + "/nowhere/flower: no such file or folder; no 'nowhere' in " + d);
  // Datasets one level down.
  CHECK(load_error(d + "/scenes") ==
        d + "/scenes: no dataset here, but its subfolder flower holds one: give " + flower);
  // Photos without poses: from-photos makes a dataset of them; in images/ too.
  touch(d + "/photos/IMG_0001.JPG");
  touch(d + "/photos/IMG_0002.png");
  touch(d + "/photos/notes.txt");
  const std::string make_them = "make a dataset of them with `mipnerf-cl dataset from-photos ";
  CHECK(load_error(d + "/photos") == d + "/photos: 2 photos (PNG or JPEG) but no camera poses; " + make_them + d +
                                         "/photos OUT` (COLMAP), then train on OUT");
  touch(d + "/capture/images/a.jpeg");
  CHECK(load_error(d + "/capture") ==
        d + "/capture: 1 photo in images/ but no camera poses (no poses_bounds.npy or transforms.json); " + make_them +
            d + "/capture/images OUT` (COLMAP), then train on OUT");
  // A COLMAP workspace: its model is imported, not made again.
  touch(d + "/capture/sparse/0/cameras.bin");
  const std::string model = d + "/capture/sparse/0";
  CHECK(load_error(d + "/capture") == d + "/capture: a COLMAP model (" + model + ") but no dataset; import it with " +
                                          "`mipnerf-cl dataset import-colmap " + model + " " + d +
                                          "/capture/images OUT`, then train on OUT");
  // An empty folder: the one place where writing the procedural scene is the likely wish.
  std::filesystem::create_directories(d + "/empty");
  const std::string fill_it =
      "put a dataset there, or write the built-in procedural scene into it with `mipnerf-cl "
      "make-scene ";
  CHECK(load_error(d + "/empty") == d + "/empty: an empty folder; " + fill_it + d + "/empty`");
}
