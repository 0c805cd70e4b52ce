// Camera paths on the host: orbits (against the procedural scene's own orbits), path files and their errors,
// and resized cameras (the same view, with the pixel footprint following the pixel size).
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "data/paths/camera_path.hpp"
#include "data/synthetic/procedural.hpp"
#include "support/temp_scene.hpp"

using namespace mipnerf;
namespace fs = std::filesystem;

namespace {

std::string write_text(const std::string& name, const std::string& text) {
  const auto dir = test::temp_path("camera-paths");
  fs::create_directories(dir);
  const std::string path = (dir / name).string();
  std::ofstream(path) << text;
  return path;
}

// A rigid pose (a rotation about z by 90° and a translation), as a JSON 4×4.
const char* kPose = "[[0,-1,0,1],[1,0,0,2],[0,0,1,3],[0,0,0,1]]";

std::array<double, 3> unit(const std::array<double, 3>& v) {
  const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  return {v[0] / n, v[1] / n, v[2] / n};
}

}  // namespace

TEST_CASE("render: orbit cameras reproduce the procedural scene's val orbit") {
  data::SceneOptions scene;
  scene.val_views = 8;
  const auto val = data::procedural_cameras("val", scene);  // 25° elevation, radius 4, around the origin, z up
  const auto first = data::camera_center(val[0]);
  data::OrbitOptions orbit;
  orbit.radius = 4.0;
  orbit.elevation_deg = 25.0;
  orbit.start_azimuth_deg = std::atan2(first[1], first[0]) * 180.0 / M_PI;
  orbit.frames = 8;
  orbit.intrinsics = val[0];
  const auto cameras = data::orbit_cameras(orbit);
  REQUIRE(cameras.size() == 8);
  for (size_t k = 0; k < 8; ++k) {
    INFO("frame " << k);
    // Both are look_at_pose of the same eye; only the azimuth's rounding differs (a few ulp of 2π).
    for (int i = 0; i < 12; ++i)
      CHECK(cameras[k].camera_to_world[i] == doctest::Approx(val[k].camera_to_world[i]).epsilon(1e-12).scale(1.0));
    CHECK(cameras[k].focal_x_px == val[k].focal_x_px);
    CHECK(cameras[k].width_px == val[k].width_px);
    CHECK(cameras[k].near == val[k].near);
  }
}

TEST_CASE("render: an orbit fitted to a capture finds its centre, up direction and radius") {
  data::SceneOptions scene;
  scene.val_views = 8;
  scene.camera_distance = 3.0;
  auto cameras = data::procedural_cameras("val", scene);  // evenly spaced: the up vectors' tilt cancels exactly
  // Move the capture: every camera shifted by (1, −2, 0.5); the fit must follow.
  for (auto& c : cameras) {
    c.camera_to_world[3] += 1.0;
    c.camera_to_world[7] -= 2.0;
    c.camera_to_world[11] += 0.5;
  }
  const auto orbit = data::orbit_around(cameras);
  // Least squares on exact look-at axes: the solution is exact up to rounding (1e-9 of the 3-unit scale).
  CHECK(orbit.target[0] == doctest::Approx(1.0).epsilon(1e-9));
  CHECK(orbit.target[1] == doctest::Approx(-2.0).epsilon(1e-9));
  CHECK(orbit.target[2] == doctest::Approx(0.5).epsilon(1e-9));
  CHECK(orbit.up[2] == doctest::Approx(1.0).epsilon(1e-12));
  CHECK(std::abs(orbit.up[0]) < 1e-12);
  CHECK(orbit.radius == doctest::Approx(3.0).epsilon(1e-12));
  CHECK(orbit.intrinsics.width_px == cameras[0].width_px);
  // With a tilted up vector the orbit stays perpendicular to it: every camera at the same height along up.
  data::OrbitOptions tilted = orbit;
  tilted.target = {1.0, -2.0, 0.5};
  tilted.up = {0.0, 1.0, 1.0};
  tilted.elevation_deg = 20.0;
  const auto u = unit(tilted.up);
  for (const auto& c : data::orbit_cameras(tilted)) {
    const auto centre = data::camera_center(c);
    const double height = (centre[0] - 1.0) * u[0] + (centre[1] + 2.0) * u[1] + (centre[2] - 0.5) * u[2];
    CHECK(height == doctest::Approx(3.0 * std::sin(20.0 * M_PI / 180.0)).epsilon(1e-12));
    // ... and looking at the target.
    const auto axis = data::optical_axis(c);
    const auto to_target = unit({1.0 - centre[0], -2.0 - centre[1], 0.5 - centre[2]});
    CHECK(axis[0] * to_target[0] + axis[1] * to_target[1] + axis[2] * to_target[2] ==
          doctest::Approx(1.0).epsilon(1e-12));
  }
  // Random views of the upper hemisphere: the mean up vector is only roughly +z; it is snapped to the axis.
  scene.train_views = 10;
  const auto random_views = data::orbit_around(data::procedural_cameras("train", scene));
  CHECK(random_views.up == Vec3{0.0, 0.0, 1.0});
  CHECK(random_views.radius == doctest::Approx(3.0).epsilon(1e-9));
  CHECK_THROWS_WITH_AS(data::orbit_around({}), doctest::Contains("no cameras"), Error);
  data::OrbitOptions bad = orbit;
  bad.elevation_deg = 90.0;
  CHECK_THROWS_WITH_AS(data::orbit_cameras(bad), doctest::Contains("elevation must lie strictly between -90 and 90"),
                       Error);
  bad = orbit;
  bad.radius = 0.0;
  CHECK_THROWS_WITH_AS(data::orbit_cameras(bad), doctest::Contains("radius must be positive"), Error);
  bad = orbit;
  bad.frames = 0;
  CHECK_THROWS_WITH_AS(data::orbit_cameras(bad), doctest::Contains("at least 1"), Error);
}

TEST_CASE("render: camera path files give intrinsics, poses and ranges, per frame over the file's") {
  const std::string file = write_text("path.json", std::string(R"({
    "fl_x": 50, "cx": 20, "cy": 10, "w": 40, "h": 20, "near": 1.5, "far": 7,
    "frames": [
      {"transform_matrix": )") + kPose + R"(},
      {"transform_matrix": )" + kPose + R"(, "fl_x": 80, "fl_y": 90, "w": 64, "h": 48, "cx": 31, "cy": 25, "far": 9,
       "camera_model": "OPENCV", "k1": -0.1, "k2": 0.01, "p1": 0.001, "p2": -0.002},
      {"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,4]]}
    ]})");
  const auto cameras = data::read_camera_path(file, {});
  REQUIRE(cameras.size() == 3);
  CHECK(cameras[0].width_px == 40);
  CHECK(cameras[0].height_px == 20);
  CHECK(cameras[0].focal_x_px == 50.0);
  CHECK(cameras[0].focal_y_px == 50.0);  // fl_y defaults to fl_x
  CHECK(cameras[0].center_x_px == 20.0);
  CHECK(cameras[0].near == 1.5);
  CHECK(cameras[0].far == 7.0);
  CHECK(cameras[0].camera_to_world[1] == -1.0);
  CHECK(cameras[0].camera_to_world[7] == 2.0);
  CHECK(cameras[1].width_px == 64);
  CHECK(cameras[1].focal_y_px == 90.0);
  CHECK(cameras[1].center_y_px == 25.0);
  CHECK(cameras[1].far == 9.0);
  CHECK(cameras[1].near == 1.5);
  CHECK(cameras[2].camera_to_world[11] == 4.0);  // a 3×4 matrix is accepted
  CHECK(cameras[0].lens.is_pinhole());             // a lens is per frame
  CHECK(cameras[1].lens.model == LensModel::opencv);
  CHECK(cameras[1].lens.k1 == -0.1);
  CHECK(cameras[1].lens.p2 == -0.002);
  // Blender style: camera_angle_x and no size; the size comes from the defaults.
  const std::string blender = write_text("blender.json", std::string(R"({"camera_angle_x": 0.6911112070083618,
    "frames": [{"transform_matrix": )") + kPose + "}]}");
  const auto b = data::read_camera_path(blender, {100, 50, 2.0, 6.0});
  REQUIRE(b.size() == 1);
  CHECK(b[0].width_px == 100);
  CHECK(b[0].focal_x_px == doctest::Approx(0.5 * 100 / std::tan(0.5 * 0.6911112070083618)).epsilon(1e-15));
  CHECK(b[0].center_y_px == 25.0);
  CHECK(b[0].near == 2.0);
  // What write_camera_path writes reads back as the same cameras.
  const std::string written = (test::temp_path("camera-paths") / "written.json").string();
  data::write_camera_path(written, cameras, {"a.png", "b.png", "c.png"});
  const auto again = data::read_camera_path(written, {});
  REQUIRE(again.size() == 3);
  for (size_t k = 0; k < 3; ++k) {
    CHECK(again[k].camera_to_world == cameras[k].camera_to_world);
    CHECK(again[k].focal_x_px == cameras[k].focal_x_px);
    CHECK(again[k].focal_y_px == cameras[k].focal_y_px);
    CHECK(again[k].center_x_px == cameras[k].center_x_px);
    CHECK(again[k].center_y_px == cameras[k].center_y_px);
    CHECK(again[k].width_px == cameras[k].width_px);
    CHECK(again[k].height_px == cameras[k].height_px);
    CHECK(again[k].near == cameras[k].near);
    CHECK(again[k].far == cameras[k].far);
    CHECK(again[k].lens.model == cameras[k].lens.model);  // the lens too: --path OUT/transforms.json renders the same
    CHECK(again[k].lens.k1 == cameras[k].lens.k1);
    CHECK(again[k].lens.k2 == cameras[k].lens.k2);
    CHECK(again[k].lens.p1 == cameras[k].lens.p1);
    CHECK(again[k].lens.p2 == cameras[k].lens.p2);
  }
}

TEST_CASE("render: every bad camera path file is one error naming the file and the frame") {
  const std::string pose = kPose;
  struct Case {
    const char* name;
    std::string text;
    const char* message;
  };
  const Case cases[] = {
      {"malformed.json", "{\"frames\": [", "malformed.json: malformed JSON at line 1"},
      {"no_frames.json", "{\"fl_x\": 10}", "no_frames.json: missing key 'frames'"},
      {"empty_frames.json", "{\"frames\": []}", "empty_frames.json: 'frames' is empty"},
      {"no_pose.json", "{\"fl_x\": 10, \"w\": 4, \"h\": 4, \"frames\": [{}]}",
       "no_pose.json: frames[0]: missing key 'transform_matrix'"},
      {"scaled_pose.json",
       "{\"fl_x\": 10, \"w\": 4, \"h\": 4, \"frames\": [{\"transform_matrix\": "
       "[[2,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]}",
       "scaled_pose.json: frames[0]: the pose's rotation is not orthonormal"},
      {"no_focal.json", "{\"w\": 4, \"h\": 4, \"frames\": [{\"transform_matrix\": " + pose + "}]}",
       "no_focal.json: frames[0]: no focal length"},
      {"no_size.json", "{\"fl_x\": 10, \"frames\": [{\"transform_matrix\": " + pose + "}]}",
       "no_size.json: frames[0]: no image size: give 'w' and 'h'"},
      {"zero_width.json", "{\"fl_x\": 10, \"w\": 0, \"h\": 4, \"frames\": [{\"transform_matrix\": " + pose + "}]}",
       "zero_width.json: 'w' must be positive"},
      {"unknown_lens.json",
       "{\"fl_x\": 10, \"w\": 4, \"h\": 4, \"camera_model\": \"THIN_PRISM_FISHEYE\", \"frames\": "
       "[{\"transform_matrix\": " + pose + "}]}",
       "unknown_lens.json: camera_model 'THIN_PRISM_FISHEYE' is not read"},
      {"bad_range.json",
       "{\"fl_x\": 10, \"w\": 4, \"h\": 4, \"frames\": [{\"transform_matrix\": " + pose +
           ", \"near\": 5, \"far\": 3}]}",
       "bad_range.json: frames[0]: near and far must satisfy 0 <= near < far"},
  };
  for (const auto& c : cases) {
    INFO(c.name);
    const std::string path = write_text(c.name, c.text);
    CHECK_THROWS_WITH_AS(data::read_camera_path(path, {}), doctest::Contains(c.message), Error);
  }
  CHECK_THROWS_WITH_AS(data::read_camera_path((test::temp_path("camera-paths") / "nowhere.json").string(), {}),
                       doctest::Contains("nowhere.json: no such file"), Error);
}

TEST_CASE("render: a resized camera sees the same view, with pixels (and cone radii) of the new size") {
  Camera camera;
  camera.width_px = 64;
  camera.height_px = 48;
  camera.focal_x_px = 70.0;
  camera.focal_y_px = 72.0;
  camera.center_x_px = 31.0;
  camera.center_y_px = 25.0;
  camera.camera_to_world = {0, -1, 0, 1, 1, 0, 0, 2, 0, 0, 1, 3};
  auto same_direction = [](const Ray& a, const Ray& b) {
    for (int i = 0; i < 3; ++i) {
      // Directions (camera-frame z = −1) of the same image point; exact up to rounding.
      if (std::abs(a.direction_world[i] - b.direction_world[i]) > 1e-12) return false;
    }
    return true;
  };
  SUBCASE("a scale factor") {
    const auto half = data::resize_camera(camera, {0.5, 0, 0});
    CHECK(half.width_px == 32);
    CHECK(half.height_px == 24);
    CHECK(half.focal_x_px == 35.0);
    CHECK(half.focal_y_px == 36.0);
    CHECK(half.center_x_px == 15.5);
    CHECK(half.center_y_px == 12.5);
    CHECK(half.lossmult == 4.0);  // a pixel covers 4 of the original ones
    // The image point (x, y) of the original is (x/2, y/2) of the half-size image.
    for (double x : {0.0, 10.5, 63.0}) {
      for (double y : {0.0, 20.25, 47.5}) {
        CHECK(same_direction(camera_ray(camera, x, y), camera_ray(half, x / 2, y / 2)));
      }
    }
    // The cone radius at t = 1 is the distance between neighbouring pixels' directions · 2/√12 (rays.cl):
    // twice as large at half the resolution.
    auto pixel_width = [](const Camera& c) {
      const auto a = camera_ray(c, 10.5, 7.5).direction_world, b = camera_ray(c, 11.5, 7.5).direction_world;
      return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
    };
    CHECK(pixel_width(half) == doctest::Approx(2.0 * pixel_width(camera)).epsilon(1e-12));
    const auto big = data::resize_camera(camera, {3.0, 0, 0});
    CHECK(big.width_px == 192);
    CHECK(pixel_width(big) == doctest::Approx(pixel_width(camera) / 3.0).epsilon(1e-12));
  }
  SUBCASE("a width alone keeps the aspect ratio") {
    const auto wide = data::resize_camera(camera, {0.0, 128, 0});
    CHECK(wide.width_px == 128);
    CHECK(wide.height_px == 96);
    CHECK(wide.focal_x_px == 140.0);
    CHECK(same_direction(camera_ray(camera, 5, 7), camera_ray(wide, 10, 14)));
    const auto tall = data::resize_camera(camera, {0.0, 0, 24});
    CHECK(tall.width_px == 32);
    CHECK(tall.center_x_px == 15.5);
  }
  SUBCASE("another aspect ratio keeps square pixels and the horizontal field of view") {
    const auto other = data::resize_camera(camera, {0.0, 128, 128});
    CHECK(other.width_px == 128);
    CHECK(other.height_px == 128);
    CHECK(other.focal_x_px == 140.0);
    CHECK(other.focal_y_px == 144.0);  // both × 2: the pixels keep their shape
    CHECK(other.center_x_px == 62.0);
    CHECK(other.center_y_px == 50.0 + 0.5 * (128 - 96));  // the extra rows are added evenly above and below
    // Left and right edges see what they saw.
    CHECK(same_direction(camera_ray(camera, 0, 25), camera_ray(other, 0, other.center_y_px)));
    CHECK(same_direction(camera_ray(camera, 64, 25), camera_ray(other, 128, other.center_y_px)));
  }
  SUBCASE("bad requests") {
    CHECK_THROWS_WITH_AS(data::resize_camera(camera, {-1.0, 0, 0}), doctest::Contains("scale factor must be positive"),
                         Error);
    CHECK_THROWS_WITH_AS(data::resize_camera(camera, {NAN, 0, 0}), doctest::Contains("scale factor must be positive"),
                         Error);
    CHECK_THROWS_WITH_AS(data::resize_camera(camera, {0.5, 10, 0}), doctest::Contains("not both"), Error);
    CHECK_THROWS_WITH_AS(data::resize_camera(camera, {0.0, 100000, 100000}),
                         doctest::Contains("more than 2^32 - 1 pixels"), Error);
    CHECK(data::resize_camera(camera, {1e-6, 0, 0}).width_px == 1);  // never below one pixel
  }
}

TEST_CASE("render: sizes are WIDTHxHEIGHT") {
  CHECK(data::parse_size("800x600", "--size") == std::pair<uint32_t, uint32_t>{800, 600});
  CHECK(data::parse_size("1X2", "--size") == std::pair<uint32_t, uint32_t>{1, 2});
  for (const char* bad : {"800", "x600", "800x", "80a0x600", "-8x6", "8x6x2", "1234567890x2", ""}) {
    INFO(bad);
    CHECK_THROWS_WITH_AS(data::parse_size(bad, "--size"), doctest::Contains("expected WIDTHxHEIGHT"), Error);
  }
  CHECK_THROWS_WITH_AS(data::parse_size("0x600", "--size"), doctest::Contains("at least 1 pixel"), Error);
}
