// COLMAP import: models written from known cameras and points (text and binary) import to transforms.json files that
// load with those cameras, recentred and rescaled; the near/far rule; distortion, missing images and every kind of
// malformed file are one-line errors naming the file (and line).
#include <doctest/doctest.h>

#include "data/image.hpp"
#include "support/jpeg_writer.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <random>

#include "core/lens_models.hpp"
#include "data/import/colmap_model.hpp"
#include "data/import/colmap_import.hpp"
#include "data/dataset.hpp"
#include "data/inspect.hpp"
#include "support/colmap_writer.hpp"
#include "support/data_fixtures.hpp"

using namespace mipnerf;
using test::contains;
using test::error_of;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A capture around `target`: `count` cameras on a circle of `radius` at height 0.4·radius, looking at it. Images
// 0..3 use camera 1 (PINHOLE 8×6, off-centre principal point), the rest camera 2 (SIMPLE_PINHOLE 6×4). Points: a
// 5×5×5 grid of half-width `half` around the target, each seen by every image.
struct KnownCapture {
  Vec3 target;
  double radius;
  double half = 0.5;
  std::vector<data::Matrix34> poses;  // OpenGL camera-to-world, by image
  test::ColmapTestModel model;

  KnownCapture(const Vec3& target_, double radius_, int count = 6) : target(target_), radius(radius_) {
    model.cameras = {{1, "PINHOLE", 1, 8, 6, {7.0, 7.5, 4.25, 2.75}}, {2, "SIMPLE_PINHOLE", 0, 6, 4, {5.0, 3.0, 2.0}}};
    for (int k = 0; k < count; ++k) {
      const double angle = 2 * kPi * k / count + 0.3;
      const Vec3 eye{target[0] + radius * std::cos(angle), target[1] + radius * std::sin(angle),
                           target[2] + 0.4 * radius};
      poses.push_back(data::look_at_pose(eye, target, {0, 0, 1}));
      // Ids deliberately not in name order: frames follow the names.
      model.images.push_back(
          test::colmap_image(100 - k, k < 4 ? 1 : 2, "img_" + std::to_string(k) + ".png", poses.back()));
    }
    uint64_t id = 1;
    for (int i = -2; i <= 2; ++i)
      for (int j = -2; j <= 2; ++j)
        for (int l = -2; l <= 2; ++l) {
          test::ColmapTestPoint point{
              id++, {target[0] + half * i / 2, target[1] + half * j / 2, target[2] + half * l / 2}, {}};
          for (const auto& image : model.images) point.image_ids.push_back(image.id);
          model.points.push_back(point);
        }
  }

  const test::ColmapTestCamera& camera_of(size_t k) const { return model.cameras[k < 4 ? 0 : 1]; }

  // Tiny PNGs of each camera's size, named as the images.
  void write_images(const std::string& dir) const {
    for (size_t k = 0; k < model.images.size(); ++k) {
      const auto& camera = camera_of(k);
      const auto rgba = test::test_rgba8(static_cast<int>(k), camera.width, camera.height);
      io::write_png8(dir + "/" + model.images[k].name, camera.width, camera.height, 4, rgba.data());
    }
  }
};

// numpy.percentile's default: linear between the sorted neighbours.
double percentile(std::vector<double> values, double q) {
  std::sort(values.begin(), values.end());
  const double position = q * (values.size() - 1);
  const size_t below = static_cast<size_t>(position);
  if (below + 1 >= values.size()) return values.back();
  return values[below] + (position - below) * (values[below + 1] - values[below]);
}

data::LoadOptions all_frames() {
  data::LoadOptions options;
  options.holdout_every = 0;
  return options;
}

std::string import_error(const std::string& sparse, const std::string& images, const std::string& out) {
  const std::string message = error_of([&] { data::import_colmap(sparse, images, out); });
  CHECK(message.find('\n') == std::string::npos);
  return message;
}

}  // namespace

TEST_CASE("colmap: the pose convention on hand-checked cameras (x_cam = R x_world + t, OpenCV axes)") {
  // Identity rotation, t = (0, 0, 5): the camera sits at -R^T t = (0, 0, -5) and looks along +z (OpenCV z forward);
  // image y points down, so its OpenGL y (up) column is -y; its -z column (the viewing direction) is +z.
  const auto identity = data::colmap_camera_to_world({1, 0, 0, 0}, {0, 0, 5});
  const data::Matrix34 expected{1, 0, 0, 0, 0, -1, 0, 0, 0, 0, -1, -5};
  for (int i = 0; i < 12; ++i) CHECK(identity[i] == expected[i]);
  Camera camera;
  camera.camera_to_world = identity;
  CHECK(data::optical_axis(camera) == Vec3{0, 0, 1});
  data::ColmapImage image;
  image.tvec = {0, 0, 5};
  CHECK(data::colmap_depth(image, {0, 0, 0}) == 5.0);
  CHECK(data::colmap_depth(image, {3, -2, 1}) == 6.0);

  // 90 degrees about z: q = (cos 45°, 0, 0, sin 45°), R = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]. The camera axes in
  // world are R's rows: x (0, -1, 0), y down (1, 0, 0), z forward (0, 0, 1); OpenGL's y and z are their negatives.
  // The centre -R^T t = -(2, -1, 3).
  const double h = std::sqrt(0.5);
  const auto turned = data::colmap_camera_to_world({h, 0, 0, h}, {1, 2, 3});
  const data::Matrix34 turned_expected{0,  -1, 0,  -2,  //
                                       -1, 0,  0,  1,   //
                                       0,  0,  -1, -3};
  for (int i = 0; i < 12; ++i) CHECK(turned[i] == doctest::Approx(turned_expected[i]).epsilon(1e-15));
  CHECK_NOTHROW(data::check_rigid_pose(turned, "turned"));

  // The test writer's quaternions (Shepperd) agree with the importer's rotation on random rotations.
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 50; ++trial) {
    const Vec3 eye{normal(rng), normal(rng), normal(rng)}, at{normal(rng), normal(rng), normal(rng)};
    const auto pose = data::look_at_pose(eye, at, {normal(rng), normal(rng), normal(rng)});
    const auto colmap = test::colmap_image(1, 1, "x.png", pose);
    const auto back = data::colmap_camera_to_world(colmap.q, colmap.t);
    for (int i = 0; i < 12; ++i) REQUIRE(back[i] == doctest::Approx(pose[i]).epsilon(1e-12).scale(1.0));
  }
}

TEST_CASE("colmap: near/far are per-image depth percentiles with a margin, robust to stray points") {
  std::vector<std::vector<double>> depths(3);
  for (int d = 1; d <= 101; ++d) depths[0].push_back(d);  // percentiles 1 and 99: 2 and 100
  const auto one = data::near_far_from_depths(depths);
  REQUIRE(one);
  CHECK(one->images == 1);
  CHECK(one->near == doctest::Approx(0.9 * 2).epsilon(1e-14));
  CHECK(one->far == doctest::Approx(1.1 * 100).epsilon(1e-14));
  // A second image of 300 depths in [2, 3] with one stray point at 1000: the percentile drops the stray point;
  // the range is the union over images.
  depths = {{}, {}};
  for (int k = 0; k < 300; ++k) depths[0].push_back(2.0 + k / 299.0);
  depths[0].push_back(1000.0);
  depths[1] = {1.5, 1.6, 1.7};
  const auto two = data::near_far_from_depths(depths);
  REQUIRE(two);
  CHECK(two->images == 2);
  CHECK(two->near == doctest::Approx(0.9 * (1.5 + 0.02 * 0.1)).epsilon(1e-12));
  CHECK(two->far < 1.1 * 3.01);
  std::vector<std::vector<double>> none(2);
  CHECK_FALSE(data::near_far_from_depths(none));
}

TEST_CASE("colmap: known cameras far from the origin import (text and binary alike) and load as they were made") {
  test::TempDir dir;
  const Vec3 target{1000.0, -2000.0, 500.0};
  const double radius = 3.0;
  KnownCapture capture(target, radius);
  capture.write_images(dir / "images");
  test::write_colmap_model(dir / "text", capture.model, false);
  test::write_colmap_model(dir / "binary", capture.model, true);
  const auto from_text = data::import_colmap(dir / "text", dir / "images", dir / "out_text");
  const auto from_binary = data::import_colmap(dir / "binary", dir / "images", dir / "out_binary");
  CHECK_FALSE(from_text.binary);
  CHECK(from_binary.binary);
  CHECK(from_text.images == 6);
  CHECK(from_text.cameras == 2);
  CHECK(from_text.points == 125);
  CHECK(from_text.camera_models == std::vector<std::string>{"PINHOLE", "SIMPLE_PINHOLE"});
  // The two files say the same but for where the model came from.
  auto text_json = io::read_json(dir / "out_text/transforms.json");
  auto binary_json = io::read_json(dir / "out_binary/transforms.json");
  CHECK(text_json["colmap"]["format"] == "text");
  CHECK(text_json["colmap"]["sparse_dir"] == "../text");
  for (auto* json : {&text_json, &binary_json}) {
    (*json)["colmap"].erase("format");
    (*json)["colmap"].erase("sparse_dir");
  }
  CHECK(text_json == binary_json);

  // Every axis passes through the target: it becomes the origin, and the cameras (all `radius`·√1.16 from it)
  // move to distance 4.
  const double distance = radius * std::sqrt(1.16);
  const double scale = data::kImportedCameraDistance / distance;
  CHECK(from_text.centre_rule == "look-at");
  for (int k = 0; k < 3; ++k) CHECK(from_text.centre[k] == doctest::Approx(target[k]).epsilon(1e-12));
  CHECK(from_text.scale == doctest::Approx(scale).epsilon(1e-10));
  CHECK(text_json["colmap"]["world"]["scale"].get<double>() == from_text.scale);

  // Near/far: the rule on the true depths of the grid, in scene units.
  double true_min = 1e30, true_max = 0;
  std::vector<std::vector<double>> depths(capture.poses.size());
  for (size_t k = 0; k < capture.poses.size(); ++k) {
    for (const auto& point : capture.model.points) {
      const double depth = test::to_colmap_camera(capture.model.images[k], point.xyz)[2];
      depths[k].push_back(depth);
      true_min = std::min(true_min, depth);
      true_max = std::max(true_max, depth);
    }
  }
  double low = 1e30, high = 0;
  for (const auto& d : depths) low = std::min(low, percentile(d, 0.01)), high = std::max(high, percentile(d, 0.99));
  CHECK(from_text.near == doctest::Approx(0.9 * low * scale).epsilon(1e-10));
  CHECK(from_text.far == doctest::Approx(1.1 * high * scale).epsilon(1e-10));
  CHECK(from_text.near < true_min * scale);  // every point is inside near..far
  CHECK(from_text.far > true_max * scale);
  CHECK(from_text.near_far_from_points);

  // Loaded by the transforms.json loader, frames in name order.
  const auto dataset = data::load_dataset(dir / "out_text/transforms.json", all_frames());
  const auto& split = dataset.split("train");
  REQUIRE(split.num_images() == 6);
  for (size_t k = 0; k < 6; ++k) {
    CAPTURE(k);
    const Camera& camera = split.cameras[k];
    // Each frame's file is a link in OUT/images to the photo (a dataset names only files in its own folder).
    CHECK(split.files[k] == (std::filesystem::path(dir.path()) / "out_text/images" /
                             ("0000" + std::to_string(k) + "_img_" + std::to_string(k) + ".png"))
                                .string());
    CHECK(std::filesystem::canonical(split.files[k]) ==
          std::filesystem::canonical(std::filesystem::path(dir.path()) / "images" / ("img_" + std::to_string(k) + ".png")));
    // Pose: the rotation as made, the centre moved and scaled.
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 3; ++col) {
        CHECK(camera.camera_to_world[row * 4 + col] ==
              doctest::Approx(capture.poses[k][row * 4 + col]).epsilon(1e-12).scale(1.0));
      }
      CHECK(camera.camera_to_world[row * 4 + 3] ==
            doctest::Approx(scale * (capture.poses[k][row * 4 + 3] - target[row])).epsilon(1e-9).scale(1.0));
    }
    // Intrinsics of its camera.
    const auto& colmap_camera = capture.camera_of(k);
    const bool simple = colmap_camera.model == "SIMPLE_PINHOLE";
    CHECK(camera.width_px == colmap_camera.width);
    CHECK(camera.height_px == colmap_camera.height);
    CHECK(camera.focal_x_px == colmap_camera.params[0]);
    CHECK(camera.focal_y_px == colmap_camera.params[simple ? 0 : 1]);
    CHECK(camera.center_x_px == colmap_camera.params[simple ? 1 : 2]);
    CHECK(camera.center_y_px == colmap_camera.params[simple ? 2 : 3]);
    CHECK(camera.near == from_text.near);
    CHECK(camera.far == from_text.far);
    // Where COLMAP projects a point (u = fx x/z + cx, v = fy y/z + cy, pixel centres at +0.5), our ray through that
    // image position passes through the point (scaled like the world).
    for (size_t p = 0; p < capture.model.points.size(); p += 17) {
      const Vec3 c = test::to_colmap_camera(capture.model.images[k], capture.model.points[p].xyz);
      const double u = camera.focal_x_px * c[0] / c[2] + camera.center_x_px;
      const double v = camera.focal_y_px * c[1] / c[2] + camera.center_y_px;
      const Ray ray = camera_ray(camera, u, v);
      // The ray's t is depth along the optical axis: at t = scaled depth it reaches the scaled point.
      const double t = c[2] * scale;
      for (int axis = 0; axis < 3; ++axis) {
        const double expected = scale * (capture.model.points[p].xyz[axis] - target[axis]);
        CHECK(ray.origin_world[axis] + t * ray.direction_world[axis] ==
              doctest::Approx(expected).scale(1.0).epsilon(1e-9));
      }
    }
  }
  // `dataset inspect` finds the cameras looking at the origin, the scene within near..far.
  const auto summary = data::summarize(split);
  REQUIRE(summary.look_at);
  for (int k = 0; k < 3; ++k) CHECK(std::abs((*summary.look_at)[k]) < 1e-9);
  CHECK(summary.cameras_facing == 6);
  CHECK(summary.radius_min == doctest::Approx(4.0).epsilon(1e-9));
  // Holdout as for any transforms.json: every 8th frame (here frame 0) is the test split.
  CHECK(data::load_dataset(dir / "out_binary").split("test").num_images() == 1);
}

TEST_CASE("colmap: a forward-facing capture is centred on the median of its points, and near/far can be overridden") {
  test::TempDir dir;
  KnownCapture capture({0, 0, 0}, 1.0, 0);
  // Four parallel cameras 10 units before a wall of points, looking along -y (OpenGL: -z is forward).
  for (int k = 0; k < 4; ++k) {
    const Vec3 eye{-1.5 + k, 10.0, 0.0};
    capture.poses.push_back(data::look_at_pose(eye, {eye[0], 0.0, 0.0}, {0, 0, 1}));
    capture.model.images.push_back(test::colmap_image(k + 1, 1, "img_" + std::to_string(k) + ".png", capture.poses[k]));
  }
  for (auto& point : capture.model.points) {
    point.xyz = {point.xyz[0] * 4, point.xyz[1] - 2.0, point.xyz[2] * 2};  // depths 11.5 .. 12.5, centre y = -2
    point.image_ids = {1, 2, 3, 4};
  }
  capture.write_images(dir / "images");
  test::write_colmap_model(dir / "sparse", capture.model, true);
  const auto imported = data::import_colmap(dir / "sparse", dir / "images", dir / "out");
  CHECK(imported.centre_rule == "points");
  CHECK(imported.centre == Vec3{0.0, -2.0, 0.0});
  // Camera distances from (0, -2, 0): sqrt(12² + 0.5²) twice, sqrt(12² + 1.5²) twice; the median is between.
  CHECK(imported.scale == doctest::Approx(4.0 / (0.5 * (std::sqrt(144.25) + std::sqrt(146.25)))).epsilon(1e-12));
  CHECK(imported.near < 11.5 * imported.scale);
  CHECK(imported.far > 12.5 * imported.scale);

  data::ColmapImportOptions options;
  options.near = 0.5;
  options.far = 9.0;
  const auto overridden = data::import_colmap(dir / "sparse", dir / "images", dir / "out", options);
  CHECK_FALSE(overridden.near_far_from_points);
  const auto split = data::load_dataset(dir / "out", all_frames()).split("train");
  CHECK(split.cameras[0].near == 0.5);
  CHECK(split.cameras[3].far == 9.0);
  CHECK(io::read_json(dir / "out/transforms.json")["colmap"]["near_far"]["from_points"] == false);

  // No points at all: near/far must be given; the centre is then the mean camera centre.
  capture.model.points.clear();
  test::write_colmap_model(dir / "nopoints", capture.model, false);
  CHECK(import_error(dir / "nopoints", dir / "images", dir / "out2") ==
        dir / "nopoints/points3D.txt" +
            ": no point lies in front of an image that sees it, so near/far cannot be "
            "chosen from the points: give both (--near, --far)");
  const auto given = data::import_colmap(dir / "nopoints", dir / "images", dir / "out2", options);
  CHECK(given.centre_rule == "cameras");
  CHECK(given.centre[1] == 10.0);
}

TEST_CASE("colmap: an image whose points all lie behind it is counted, and an import can leave it out") {
  test::TempDir dir;
  KnownCapture capture({0, 0, 0}, 1.0, 0);
  // Three cameras 10 units before a wall of points (as above), and a fourth beside them looking away from it: the
  // pose COLMAP once gave a photo, registered with every one of its points behind it.
  for (int k = 0; k < 4; ++k) {
    const Vec3 eye{-1.5 + k, 10.0, 0.0};
    const Vec3 target = k < 3 ? Vec3{eye[0], 0.0, 0.0} : Vec3{eye[0], 20.0, 0.0};
    capture.poses.push_back(data::look_at_pose(eye, target, {0, 0, 1}));
    capture.model.images.push_back(test::colmap_image(k + 1, 1, "img_" + std::to_string(k) + ".png", capture.poses[k]));
  }
  for (auto& point : capture.model.points) {
    point.xyz = {point.xyz[0] * 4, point.xyz[1] - 2.0, point.xyz[2] * 2};
    point.image_ids = {1, 2, 3, 4};
  }
  const size_t n_points = capture.model.points.size();
  capture.model.points[0].image_ids = {1, 2, 3};  // one point the first three see and the fourth does not
  capture.write_images(dir / "images");
  test::write_colmap_model(dir / "sparse", capture.model, true);
  const data::ColmapModel model = data::read_colmap_model(dir / "sparse");
  CHECK(data::points_in_front_counts(model) == std::vector<size_t>{n_points, n_points, n_points, 0});

  data::ColmapImportOptions options;
  options.leave_out = {"img_3.png"};
  const auto imported = data::import_colmap(dir / "sparse", dir / "images", dir / "out", options);
  CHECK(imported.images == 3);
  const auto frames = io::read_json(dir / "out/transforms.json")["frames"];
  REQUIRE(frames.size() == 3);
  for (const auto& frame : frames) CHECK_FALSE(contains(frame["file_path"].get<std::string>(), "img_3"));
  // The near/far rule sees only the images imported: the same as a model without the fourth image.
  capture.model.images.pop_back();
  for (auto& point : capture.model.points) {
    if (point.image_ids.size() == 4) point.image_ids.pop_back();
  }
  test::write_colmap_model(dir / "three", capture.model, true);
  const auto three = data::import_colmap(dir / "three", dir / "images", dir / "out_three");
  CHECK(imported.near == three.near);
  CHECK(imported.far == three.far);

  options.leave_out = {"img_0.png", "img_1.png", "img_2.png", "img_3.png"};
  CHECK(contains(error_of([&] { data::import_colmap(dir / "sparse", dir / "images", dir / "out4", options); }),
                 "every image is left out"));
}

TEST_CASE("colmap: lens cameras import with their model, and unknown, non-finite and folding lenses are refused") {
  test::TempDir dir;
  KnownCapture capture({0, 0, 0}, 4.0, 2);
  capture.write_images(dir / "images");
  capture.model.cameras[0] = {1, "SIMPLE_RADIAL", 2, 8, 6, {7.0, 4.0, 3.0, -0.02}};
  test::write_colmap_model(dir / "text", capture.model, false);
  data::import_colmap(dir / "text", dir / "images", dir / "out_radial", {});
  const auto radial = data::load_dataset(dir / "out_radial/transforms.json", all_frames()).split("train");
  REQUIRE(radial.cameras.size() == 2);
  CHECK(radial.cameras[0].lens.model == LensModel::simple_radial);
  CHECK(radial.cameras[0].lens.k1 == -0.02);

  capture.model.cameras[0] = {1, "OPENCV", 4, 8, 6, {7.0, 7.0, 4.0, 3.0, 0.1, 0.01, 0.001, 0.002}};
  test::write_colmap_model(dir / "binary", capture.model, true);
  data::import_colmap(dir / "binary", dir / "images", dir / "out_opencv", {});
  const auto opencv = data::load_dataset(dir / "out_opencv/transforms.json", all_frames()).split("train");
  CHECK(opencv.cameras[1].lens.model == LensModel::opencv);
  CHECK(opencv.cameras[1].lens.p2 == 0.002);

  // FULL_OPENCV: its eight coefficients in COLMAP's order k1, k2, p1, p2, k3, k4, k5, k6 (core/lens_models.cpp).
  capture.model.cameras[0] = {1, "FULL_OPENCV", 6, 8, 6,
                              {7.0, 7.0, 4.0, 3.0, 0.1, 0.01, 0.001, 0.002, 0.003, 0.02, 0.004, 0.0005}};
  test::write_colmap_model(dir / "full", capture.model, true);
  data::import_colmap(dir / "full", dir / "images", dir / "out_full", {});
  const auto full = data::load_dataset(dir / "out_full/transforms.json", all_frames()).split("train");
  const Lens& full_lens = full.cameras[0].lens;
  CHECK(full_lens.model == LensModel::full_opencv);
  CHECK(full_lens.k1 == 0.1);
  CHECK(full_lens.k2 == 0.01);
  CHECK(full_lens.p1 == 0.001);
  CHECK(full_lens.p2 == 0.002);
  CHECK(full_lens.k3 == 0.003);
  CHECK(full_lens.k4 == 0.02);
  CHECK(full_lens.k5 == 0.004);
  CHECK(full_lens.k6 == 0.0005);

  capture.model.cameras[0] = {1, "FOV", 7, 8, 6, {7.0, 7.0, 4.0, 3.0, 0.9}};
  test::write_colmap_model(dir / "fov", capture.model, false);
  CHECK(import_error(dir / "fov", dir / "images", dir / "out") ==
        dir / "fov/cameras.txt" +
            ":4: camera 1 is FOV, a model mipnerf-cl does not read (it reads SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, "
            "RADIAL, OPENCV, OPENCV_FISHEYE and FULL_OPENCV): run COLMAP's image_undistorter first and import the sparse model and "
            "images it writes (PINHOLE cameras)");
  capture.model.cameras[0] = {1, "RADIAL", 3, 8, 6, {7.0, 4.0, 3.0, -0.02, std::numeric_limits<double>::infinity()}};
  test::write_colmap_model(dir / "infinite", capture.model, true);
  CHECK(import_error(dir / "infinite", dir / "images", dir / "out") ==
        dir / "infinite/cameras.bin" + ": camera record 1 of 2: camera 1: its RADIAL parameter 5 of 5 is not finite");
  // k1 = −3 folds at r = 1/3 (normalised); the 8×6 image at focal 3 px reaches r = 1.6 at its corners.
  capture.model.cameras[0] = {1, "SIMPLE_RADIAL", 2, 8, 6, {3.0, 4.0, 3.0, -3.0}};
  test::write_colmap_model(dir / "fold", capture.model, false);
  CHECK(import_error(dir / "fold", dir / "images", dir / "out") ==
        dir / "fold/cameras.txt" +
            ":4: camera 1: its SIMPLE_RADIAL lens cannot be inverted at pixel (0, 0): no ray leaves the lens there (the "
            "distortion folds the image, or the pixel lies beyond the lens's field); check the coefficients (a lens "
            "COLMAP estimates is invertible over its image)");
  CHECK_FALSE(std::filesystem::exists(dir / "out/transforms.json"));
}

TEST_CASE("colmap: images missing, not PNG, or of another size than their camera are one line naming them") {
  test::TempDir dir;
  KnownCapture capture({0, 0, 0}, 4.0, 6);
  capture.write_images(dir / "images");
  test::write_colmap_model(dir / "sparse", capture.model, false);
  std::filesystem::remove(dir / "images/img_1.png");
  std::filesystem::remove(dir / "images/img_4.png");
  CHECK(import_error(dir / "sparse", dir / "images", dir / "out") ==
        dir / "images" + ": 2 of the 6 images of " + dir / "sparse/images.txt" + " are missing: img_1.png, img_4.png");
  CHECK(contains(import_error(dir / "sparse", dir / "nowhere", dir / "out"), "nowhere: no such folder"));

  // A JPEG name without the JPEG finds the PNG beside it; a JPEG is used as it is; a file of another type, or a
  // PNG named .jpg, is one line.
  capture.write_images(dir / "images");
  capture.model.images[2].name = "img_2.jpg";
  test::write_colmap_model(dir / "sparse", capture.model, false);
  CHECK_NOTHROW(data::import_colmap(dir / "sparse", dir / "images", dir / "out"));
  CHECK(io::read_json(dir / "out/transforms.json")["frames"][2]["file_path"] == "images/00002_img_2.png");
  {
    const data::RgbaImage png = data::load_rgba_image(dir / "images/img_2.png");
    std::vector<float> rgb;
    for (size_t p = 0; p < png.rgba.size() / 4; ++p) rgb.insert(rgb.end(), png.rgba.begin() + 4 * p, png.rgba.begin() + 4 * p + 3);
    test::write_jpeg(dir / "images/img_2.jpg", png.width, png.height, rgb);
  }
  CHECK_NOTHROW(data::import_colmap(dir / "sparse", dir / "images", dir / "out"));
  CHECK(io::read_json(dir / "out/transforms.json")["frames"][2]["file_path"] == "images/00002_img_2.jpg");
  // Images are told apart by their content, as the loader reads them: a PNG named .jpg is the PNG it is, and a
  // file that is neither, named .jpg, is refused as a JPEG, naming it.
  std::filesystem::remove(dir / "images/img_2.jpg");
  std::filesystem::rename(dir / "images/img_2.png", dir / "images/img_2.jpg");
  CHECK_NOTHROW(data::import_colmap(dir / "sparse", dir / "images", dir / "out"));
  CHECK(data::read_image_size(dir / "images/img_2.jpg").width == capture.model.cameras[0].width);
  CHECK(data::load_rgba_image(dir / "images/img_2.jpg").width == capture.model.cameras[0].width);
  std::filesystem::copy_file(dir / "images/img_2.jpg", dir / "images/img_2.keep");
  std::ofstream(dir / "images/img_2.jpg", std::ios::binary) << "neither a PNG nor a JPEG";
  CHECK(contains(import_error(dir / "sparse", dir / "images", dir / "out"), "img_2.jpg: not a JPEG file"));
  std::filesystem::rename(dir / "images/img_2.keep", dir / "images/img_2.jpg");
  std::filesystem::rename(dir / "images/img_2.jpg", dir / "images/img_2.tif");
  capture.model.images[2].name = "img_2.tif";
  test::write_colmap_model(dir / "sparse", capture.model, false);
  CHECK(contains(import_error(dir / "sparse", dir / "images", dir / "out"),
                 "images: img_2.tif are neither PNG nor JPEG and have no .png beside them"));
  std::filesystem::rename(dir / "images/img_2.tif", dir / "images/img_2.png");
  capture.model.images[2].name = "img_2.png";

  // Images of the distorted capture with the undistorted model (or the other way round) differ in size.
  const auto rgba = test::test_rgba8(0, 10, 6);
  io::write_png8(dir / "images/img_3.png", 10, 6, 4, rgba.data());
  test::write_colmap_model(dir / "sparse", capture.model, false);
  CHECK(import_error(dir / "sparse", dir / "images", dir / "out") ==
        dir / "images/img_3.png" + ": the image is 10x6 but its camera 1 in " + dir / "sparse/cameras.txt" +
            " is 8x6: give the images the model was made from (after image_undistorter: its images folder)");
  test::write_text_file(dir / "images/img_3.png", "not a png");
  CHECK(contains(import_error(dir / "sparse", dir / "images", dir / "out"), "img_3.png: unreadable PNG"));
}

TEST_CASE("colmap: a folder without a model says what it expected") {
  test::TempDir dir;
  std::filesystem::create_directories(dir / "sparse/0");
  test::write_text_file(dir / "sparse/cameras.txt", "");
  CHECK(import_error(dir / "sparse", dir.path(), dir / "out") ==
        dir / "sparse" +
            ": no COLMAP sparse model: expected cameras, images and points3D (.bin or .txt), found "
            "cameras.txt (COLMAP's mapper writes its models to sparse/0, sparse/1, ...: give one)");
  CHECK(import_error(dir / "none", dir.path(), dir / "out") ==
        dir / "none" + ": no such folder (expected a COLMAP sparse model)");
  // Both formats present: binary wins, as in COLMAP.
  KnownCapture capture({0, 0, 0}, 4.0, 2);
  test::write_colmap_model(dir / "both", capture.model, false);
  test::write_colmap_model(dir / "both", capture.model, true);
  CHECK(data::read_colmap_model(dir / "both").binary);
}

TEST_CASE("colmap: malformed text files are one line naming the file, the line and what is wrong") {
  const KnownCapture capture({0, 0, 0}, 4.0, 2);
  const std::string cameras = test::colmap_cameras_text(capture.model);
  const std::string images = test::colmap_images_text(capture.model);
  const std::string points = test::colmap_points_text(capture.model);
  auto camera_error = [](const std::string& text) {
    return error_of([&] { data::parse_colmap_cameras_text(text, "m/cameras.txt"); });
  };
  auto image_error = [](const std::string& text) {
    return error_of([&] { data::parse_colmap_images_text(text, "m/images.txt"); });
  };
  auto point_error = [](const std::string& text) {
    return error_of([&] { data::parse_colmap_points_text(text, "m/points3D.txt"); });
  };
  // The files as written parse; comments, blank lines and CRLF line ends are fine.
  CHECK(data::parse_colmap_cameras_text(cameras, "c").size() == 2);
  CHECK(data::parse_colmap_images_text(images, "i").size() == 2);
  CHECK(data::parse_colmap_points_text(points, "p").size() == 125);
  CHECK(data::parse_colmap_cameras_text("# c\r\n\r\n1 PINHOLE 8 6 7 7.5 4 3\r\n", "c")[0].params[3] == 3.0);
  const auto spaced = data::parse_colmap_images_text("1 1 0 0 0 0 0 0 1 my image.png\n\n2 1 0 0 0 0 0 0 1 b.png", "i");
  REQUIRE(spaced.size() == 2);
  CHECK(spaced[0].name == "my image.png");
  CHECK(spaced[1].num_points2d == 0);

  const std::vector<std::pair<std::string, std::string>> camera_cases = {
      {"1 PINHOLE 8 6 7 7.5 4\n", "m/cameras.txt:1: camera 1: PINHOLE takes 4 parameters, the line has 3"},
      {"1 PINHOLE 8 6 7 7.5 4 3 9\n", "m/cameras.txt:1: camera 1: PINHOLE takes 4 parameters, the line has 5"},
      {"\n7 FANCY 8 6 1 2 3\n", "m/cameras.txt:2: camera 7: unknown camera model 'FANCY'"},
      {"x PINHOLE 8 6 7 7 4 3\n", "m/cameras.txt:1: CAMERA_ID must be a non-negative integer, got 'x'"},
      {"1 PINHOLE 8 6 nan 7 4 3\n", "m/cameras.txt:1: camera 1: its PINHOLE parameter 1 of 4 is not finite ('nan')"},
      {"1 PINHOLE 8 6 7 7 4 3e999\n", "m/cameras.txt:1: camera 1: its PINHOLE parameter 4 of 4 must be a number, got '3e999'"},
      {"1 PINHOLE 0 6 7 7 4 3\n", "m/cameras.txt:1: camera 1: image size 0x6 is not a camera's"},
      {"1 PINHOLE 8\n", "m/cameras.txt:1: expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS..., got 3 fields"},
      {"99999999999 PINHOLE 8 6 7 7 4 3\n", "m/cameras.txt:1: CAMERA_ID '99999999999' is out of range"},
  };
  for (const auto& entry : camera_cases) {
    // Named references, not a structured binding: CAPTURE/INFO capture them in a lambda (clang 14 refuses bindings).
    const std::string& text = entry.first;
    const std::string& expected = entry.second;
    CAPTURE(text);
    const std::string message = camera_error(text);
    CHECK(contains(message, expected));
    CHECK(message.find('\n') == std::string::npos);
  }
  const std::string pose = " 0.5 0.5 0.5 0.5 1 2 3 1 a.png\n";
  const std::vector<std::pair<std::string, std::string>> image_cases = {
      {"5 0 0 0 0 1 2 3 1 a.png\n", "m/images.txt:1: image 5: the quaternion (QW QX QY QZ) is zero: not a rotation"},
      {"5 1 1 0 0 1 2 3 1 a.png\n", "m/images.txt:1: image 5: the quaternion (QW QX QY QZ) has norm 1.41"},
      {"5 1 0 0 0 1 inf 3 1 a.png\n", "m/images.txt:1: image 5: TY is not finite ('inf')"},
      {"5 1 0 0 0 1 2 3 1\n", "m/images.txt:1: expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME, got 9 fields"},
      {"#\n5" + pose + "1 2 3 4\n",
       "m/images.txt:3: the keypoints of image 5 must be X Y POINT3D_ID triples, the line has 4"},
      {"5" + pose + "1 2 x\n", "m/images.txt:2: POINT3D_ID must be an integer, got 'x'"},
      {"5" + pose + "1 2 -2\n", "m/images.txt:2: POINT3D_ID must be -1 (none) or an id, got '-2'"},
      {"5" + pose + "1 nan 7\n", "m/images.txt:2: a keypoint's Y is not finite"},
      {"5 0.5 0.5 0.5 0.5 1 2 3 -1 a.png\n",
       "m/images.txt:1: image 5: CAMERA_ID must be a non-negative integer, got '-1'"},
      {"5 0.5 0.5 0.5 0.5 1 2 3 1 a\x01.png\n", "m/images.txt:1: image 5: the image name holds a control character"},
      {"5 0.5 0.5 0.5 0.5 1 2 3 1 a\xc3(.png\n", "m/images.txt:1: image 5: the image name is not valid UTF-8"},
  };
  for (const auto& entry : image_cases) {
    // Named references, not a structured binding: CAPTURE/INFO capture them in a lambda (clang 14 refuses bindings).
    const std::string& text = entry.first;
    const std::string& expected = entry.second;
    CAPTURE(text);
    const std::string message = image_error(text);
    CHECK(contains(message, expected));
    CHECK(message.find('\n') == std::string::npos);
  }
  CHECK(data::parse_colmap_images_text("5" + pose + "1 2 -1 3 4 7\n", "i")[0].num_points2d == 2);
  CHECK(data::parse_colmap_images_text("5 0.5 0.5 0.5 0.5 1 2 3 1 caf\xc3\xa9.png\n", "i")[0].name ==
        "caf\xc3\xa9.png");
  const std::vector<std::pair<std::string, std::string>> point_cases = {
      {"1 0 0 0 1 2 3 0.5 4\n",
       "m/points3D.txt:1: expected POINT3D_ID X Y Z R G B ERROR and IMAGE_ID POINT2D_IDX pairs, got 9"},
      {"1 0 0 0 1 2 3\n", "got 7 fields"},
      {"1 0 NaN 0 1 2 3 0.5 4 0\n", "m/points3D.txt:1: Y is not finite ('NaN')"},
      {"1 0 0 0 1 2 300 0.5 4 0\n", "m/points3D.txt:1: a colour (0 to 255) '300' is out of range"},
      {"1 0 0 0 1 2 3 0.5 4 x\n", "m/points3D.txt:1: a track's POINT2D_IDX must be a non-negative integer, got 'x'"},
  };
  for (const auto& entry : point_cases) {
    // Named references, not a structured binding: CAPTURE/INFO capture them in a lambda (clang 14 refuses bindings).
    const std::string& text = entry.first;
    const std::string& expected = entry.second;
    CAPTURE(text);
    const std::string message = point_error(text);
    CHECK(contains(message, expected));
    CHECK(message.find('\n') == std::string::npos);
  }
}

TEST_CASE("colmap: models whose files disagree are one line naming the record") {
  test::TempDir dir;
  KnownCapture capture({0, 0, 0}, 4.0, 2);
  capture.model.images[1].camera_id = 9;
  test::write_colmap_model(dir / "text", capture.model, false);
  CHECK(error_of([&] { data::read_colmap_model(dir / "text"); }) ==
        dir / "text/images.txt" + ":7: image 99 (img_1.png) refers to camera 9, which cameras.txt does not list");
  test::write_colmap_model(dir / "binary", capture.model, true);
  CHECK(error_of([&] { data::read_colmap_model(dir / "binary"); }) ==
        dir / "binary/images.bin" + ": image 99 (img_1.png) refers to camera 9, which cameras.bin does not list");
  capture.model.images[1].camera_id = 1;
  capture.model.points[3].image_ids.push_back(55);
  test::write_colmap_model(dir / "text", capture.model, false);
  CHECK(error_of([&] { data::read_colmap_model(dir / "text"); }) ==
        dir / "text/points3D.txt" + ":6: point 4: its track names image 55, which images.txt does not list");
  capture.model.points[3].image_ids.pop_back();
  capture.model.cameras[1].id = 1;
  test::write_colmap_model(dir / "text", capture.model, false);
  CHECK(error_of([&] { data::read_colmap_model(dir / "text"); }) ==
        dir / "text/cameras.txt" + ":5: camera 1 is listed twice");
  capture.model.cameras[1].id = 2;
  capture.model.images.clear();
  test::write_colmap_model(dir / "text", capture.model, false);
  CHECK(contains(error_of([&] { data::read_colmap_model(dir / "text"); }),
                 dir / "text/images.txt" + ": no images: the model registered none"));
}

TEST_CASE("colmap: malformed binary files: huge counts, unknown models, bad quaternions, NaN, trailing bytes") {
  const KnownCapture capture({0, 0, 0}, 4.0, 2);
  const std::string cameras = test::colmap_cameras_binary(capture.model);
  const std::string images = test::colmap_images_binary(capture.model);
  const std::string points = test::colmap_points_binary(capture.model);
  auto patched = [](std::string bytes, size_t at, const auto& value) {
    std::memcpy(bytes.data() + at, &value, sizeof(value));
    return bytes;
  };
  auto cameras_error = [](const std::string& bytes) {
    return error_of([&] { data::parse_colmap_cameras_binary(bytes, "m/cameras.bin"); });
  };
  auto images_error = [](const std::string& bytes) {
    return error_of([&] { data::parse_colmap_images_binary(bytes, "m/images.bin"); });
  };
  auto points_error = [](const std::string& bytes) {
    return error_of([&] { data::parse_colmap_points_binary(bytes, "m/points3D.bin"); });
  };
  CHECK(data::parse_colmap_cameras_binary(cameras, "c").size() == 2);
  CHECK(data::parse_colmap_images_binary(images, "i").size() == 2);
  CHECK(data::parse_colmap_points_binary(points, "p").size() == 125);

  // Counts read from the file are checked against the bytes that follow before anything is allocated.
  const uint64_t huge = uint64_t{1} << 60;
  CHECK(cameras_error(patched(cameras, 0, huge)) ==
        "m/cameras.bin: the number of cameras is 1152921504606846976 but only " + std::to_string(cameras.size() - 8) +
            " bytes follow (each takes at least 40): the file is truncated or damaged");
  CHECK(contains(images_error(patched(images, 0, huge)), "m/images.bin: the number of images is 1152921504606846976"));
  CHECK(
      contains(points_error(patched(points, 0, huge)), "m/points3D.bin: the number of points is 1152921504606846976"));
  // Image record 1: id (4), 7 doubles (56), camera id (4), "img_0.png\0" (10), then its keypoint count.
  CHECK(contains(images_error(patched(images, 8 + 4 + 56 + 4 + 10, huge)),
                 "m/images.bin: image record 1 of 2: the number of keypoints is 1152921504606846976 but only"));
  // Point record 1: id (8), xyz (24), rgb (3), error (8), then its track length.
  CHECK(contains(points_error(patched(points, 8 + 8 + 24 + 3 + 8, huge)),
                 "m/points3D.bin: point record 1 of 125: the track length is 1152921504606846976 but only"));
  // Camera record 1: id, then the model id.
  CHECK(cameras_error(patched(cameras, 8 + 4, int32_t{42})) ==
        "m/cameras.bin: camera record 1 of 2: camera 1: unknown camera model id 42");
  CHECK(
      contains(cameras_error(patched(cameras, 8 + 4 + 4, uint64_t{0})), "camera 1: image size 0x6 is not a camera's"));
  CHECK(cameras_error(patched(cameras, 8 + 24, std::numeric_limits<double>::quiet_NaN())) ==
        "m/cameras.bin: camera record 1 of 2: camera 1: its PINHOLE parameter 1 of 4 is not finite");
  // The quaternion of image record 1 (after its id): zero, then scaled by 2.
  std::string zero = images;
  for (int k = 0; k < 4; ++k) zero = patched(zero, 8 + 4 + 8 * k, 0.0);
  CHECK(images_error(zero) ==
        "m/images.bin: image record 1 of 2: image 100: the quaternion (QW QX QY QZ) is zero: not a rotation");
  std::string doubled = images;
  for (int k = 0; k < 4; ++k) doubled = patched(doubled, 8 + 4 + 8 * k, 2.0 * capture.model.images[0].q[k]);
  CHECK(contains(images_error(doubled), "image 100: the quaternion (QW QX QY QZ) has norm 2, not 1"));
  CHECK(images_error(patched(images, 8 + 4 + 40, std::numeric_limits<double>::infinity())) ==
        "m/images.bin: image record 1 of 2: the translation is not finite");
  CHECK(points_error(patched(points, 8 + 8 + 16, std::numeric_limits<double>::quiet_NaN())) ==
        "m/points3D.bin: point record 1 of 125: the position is not finite");
  // A name without its terminating NUL, and bytes after the last record.
  std::string unterminated = test::colmap_images_binary({{}, {capture.model.images[0]}, {}});
  unterminated.resize(unterminated.size() - 8);  // drop the keypoint count ...
  unterminated.back() = 'x';                     // ... and the NUL
  CHECK(
      contains(images_error(unterminated), "m/images.bin: image record 1 of 1: truncated: the name (NUL-terminated)"));
  CHECK(cameras_error(cameras + "xyz") ==
        "m/cameras.bin: 3 bytes follow the last camera: the file is damaged or not a COLMAP cameras file");
  CHECK(
      contains(points_error(points.substr(0, 5)), "m/points3D.bin: truncated: the number of points needs 8 bytes, 5"));
}

TEST_CASE("colmap: every truncation and random damage of a file parses or is a mipnerf::Error naming the file") {
  const KnownCapture capture({0, 0, 0}, 4.0, 3);
  using Parser = void (*)(std::string_view, const std::string&);
  // Binary files must fail on every truncation; text files may still parse (a truncation at a line end).
  const std::vector<std::tuple<std::string, std::string, Parser>> files = {
      {"m/cameras.txt", test::colmap_cameras_text(capture.model),
       [](std::string_view b, const std::string& w) { data::parse_colmap_cameras_text(b, w); }},
      {"m/images.txt", test::colmap_images_text(capture.model),
       [](std::string_view b, const std::string& w) { data::parse_colmap_images_text(b, w); }},
      {"m/points3D.txt", test::colmap_points_text(capture.model),
       [](std::string_view b, const std::string& w) { data::parse_colmap_points_text(b, w); }},
      {"m/cameras.bin", test::colmap_cameras_binary(capture.model),
       [](std::string_view b, const std::string& w) { data::parse_colmap_cameras_binary(b, w); }},
      {"m/images.bin", test::colmap_images_binary(capture.model),
       [](std::string_view b, const std::string& w) { data::parse_colmap_images_binary(b, w); }},
      {"m/points3D.bin", test::colmap_points_binary(capture.model),
       [](std::string_view b, const std::string& w) { data::parse_colmap_points_binary(b, w); }},
  };
  std::mt19937 rng(11);
  for (const auto& file : files) {
    const std::string& name = std::get<0>(file);
    const std::string& bytes = std::get<1>(file);
    const Parser& parse = std::get<2>(file);
    CAPTURE(name);
    auto outcome = [&](const std::string& damaged) {
      try {
        parse(damaged, name);
        return true;
      } catch (const Error& e) {
        const std::string message = e.what();
        REQUIRE(message.rfind(name + ":", 0) == 0);
        REQUIRE(message.find('\n') == std::string::npos);
        return false;
      }
      // Any other exception escapes and fails the test.
    };
    const bool binary = name.back() == 'n';
    for (size_t size = 0; size < bytes.size(); size += binary ? 1 : 7) {
      const bool parsed = outcome(bytes.substr(0, size));
      if (binary) REQUIRE_FALSE(parsed);
    }
    // Random bytes, and for text the characters numbers and lines are made of.
    const std::string characters = " \n#-.0123456789eEnaif\t\x01\xff";
    std::uniform_int_distribution<size_t> where(0, bytes.size() - 1);
    std::uniform_int_distribution<int> value(0, 255);
    for (int trial = 0; trial < 3000; ++trial) {
      std::string damaged = bytes;
      const int changes = 1 + trial % 4;
      for (int c = 0; c < changes; ++c) {
        damaged[where(rng)] = trial % 2 ? static_cast<char>(value(rng)) : characters[value(rng) % characters.size()];
      }
      outcome(damaged);
    }
  }
}

// A dataset names only files in its own folder (data/path_policy.hpp): the importer links the photos into OUT/images
// and names those; an image name in the model that climbs out of the images folder is refused.
TEST_CASE("colmap: the imported transforms.json names links inside its folder, and a name out of the images is refused") {
  test::TempDir dir;
  KnownCapture capture({0, 0, 0}, 4.0);
  capture.write_images(dir / "images");
  test::write_colmap_model(dir / "sparse", capture.model, false);
  data::ColmapImportOptions options;
  options.layout = data::ImportLayout::transforms_json;
  data::import_colmap(dir / "sparse", dir / "images", dir / "out", options);
  const io::Json written = io::read_json(dir / "out/transforms.json");
  for (const auto& frame : written["frames"]) {
    const std::string path = frame["file_path"].get<std::string>();
    CAPTURE(path);
    CHECK(path.rfind("images/", 0) == 0);
    CHECK(std::filesystem::exists(std::filesystem::path(dir / "out") / path));
  }
  CHECK(data::load_dataset(dir / "out/transforms.json", all_frames()).split("train").cameras.size() ==
        capture.model.images.size());

  // One image named "../images/img_0.png": it exists, but outside the images folder given.
  capture.model.images[0].name = "../images/" + capture.model.images[0].name;
  test::write_colmap_model(dir / "escape", capture.model, false);
  const std::string message = import_error(dir / "escape", dir / "images", dir / "out2");
  CHECK(contains(message, "escape/images.txt: image 100's name '../images/img_0.png' lies outside " + dir / "images"));
  CHECK(message.find('\n') == std::string::npos);
}

TEST_CASE("colmap: every lens row (core/lens_models.cpp) is COLMAP's model of that name: id and parameter count") {
  for (const auto& row : lens_rows()) {
    INFO(row.colmap_name);
    const data::ColmapCameraModel* by_name = data::find_colmap_camera_model(row.colmap_name);
    REQUIRE(by_name);
    CHECK(by_name->id == row.colmap_id);
    CHECK(static_cast<size_t>(by_name->num_params) == row.parameter_count());
    CHECK(find_lens_row(row.colmap_name) == &row);
  }
  CHECK(find_lens_row("FOV") == nullptr);
}
