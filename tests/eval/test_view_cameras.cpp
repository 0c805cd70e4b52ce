// The cameras `mipnerf-cl render` draws (eval/view_cameras.hpp): a split's views with their scales and names, an
// orbit with and without training cameras to fit, a camera path file, and the near/far override.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>

#include "core/error.hpp"
#include "data/paths/camera_path.hpp"
#include "eval/view_cameras.hpp"
#include "io/json.hpp"
#include "io/png.hpp"
#include "render_fixtures.hpp"

using namespace mipnerf;
namespace fs = std::filesystem;

namespace {

double distance_from_origin(const Camera& c) {
  const auto& m = c.camera_to_world;  // the translation is the last column of the 3×4
  return std::sqrt(m[3] * m[3] + m[7] * m[7] + m[11] * m[11]);
}

}  // namespace

TEST_CASE("view cameras: an orbit without training cameras is Blender's camera around the origin") {
  const train::TrainedModel model;  // records no data: nothing to fit the orbit to
  eval::OrbitRequest request;
  request.radius = 5.0;
  request.frames = 8;
  request.fov_deg = 90.0;
  const eval::ViewFrames frames = eval::orbit_views(model, request, {});
  REQUIRE(frames.cameras.size() == 8);
  CHECK(frames.stems.front() == "frame_0000");
  CHECK(frames.stems.back() == "frame_0007");
  CHECK(frames.default_folder == "render_orbit");
  CHECK(frames.source == "an orbit");
  CHECK(frames.details["kind"] == "orbit");
  CHECK(frames.details["fitted_to_training_cameras"] == false);
  CHECK(frames.details["frames"] == 8);
  for (const auto& c : frames.cameras) {
    CHECK(c.width_px == 400);
    CHECK(c.height_px == 400);
    CHECK(c.near == 2.0);  // the model sets no near/far: Blender's
    CHECK(c.far == 6.0);
    CHECK(c.focal_x_px == doctest::Approx(200.0).epsilon(1e-12));  // 90°: half the width over tan 45°
    CHECK(distance_from_origin(c) == doctest::Approx(5.0).epsilon(1e-12));
  }
}

TEST_CASE("view cameras: an orbit fitted to the training cameras takes their size, resized on request") {
  train::TrainedModel model;
  model.data_path = test::render_scene();
  eval::OrbitRequest request;
  request.frames = 3;
  request.focal_px = 30.0;
  data::ResolutionRequest half;
  half.scale = 0.5;
  const eval::ViewFrames frames = eval::orbit_views(model, request, half);
  REQUIRE(frames.cameras.size() == 3);
  CHECK(frames.details["fitted_to_training_cameras"] == true);
  CHECK(frames.cameras[0].width_px == 8);  // the scene's 16×16 training views, halved
  CHECK(frames.cameras[0].focal_x_px == 30.0);
  CHECK(eval::training_cameras(model, "").size() == 8);
  CHECK(eval::training_cameras(train::TrainedModel{}, "").empty());
}

TEST_CASE("view cameras: a split's first view with all its scales, then a near and far range") {
  train::TrainedModel model;
  model.data_path = test::render_scene();
  eval::SplitViewRequest request;
  request.views = 1;
  request.scales = 2;
  data::ResolutionRequest half;
  half.scale = 0.5;
  eval::ViewFrames frames = eval::split_views(model, "ckpt.mnck", request, half);
  REQUIRE(frames.cameras.size() == 2);  // view 0 at full resolution and ×2 downsampled
  CHECK(frames.cameras[0].width_px == 8);
  CHECK(frames.cameras[1].width_px == 4);
  CHECK(frames.stems[0] != frames.stems[1]);
  CHECK(frames.stems[1].find("_scale1") != std::string::npos);
  CHECK(frames.default_folder == "render_test");
  CHECK(frames.source == "the test split of " + test::render_scene());
  CHECK(frames.details["kind"] == "split");
  CHECK(frames.details["split"] == "test");

  eval::apply_depth_range(frames.cameras, 1.0, 3.0);
  for (const auto& c : frames.cameras) {
    CHECK(c.near == 1.0);
    CHECK(c.far == 3.0);
  }
  eval::apply_depth_range(frames.cameras, std::nullopt, 4.0);  // only far: near stays
  CHECK(frames.cameras[0].near == 1.0);
  CHECK(frames.cameras[0].far == 4.0);
  CHECK_THROWS_WITH_AS(eval::apply_depth_range(frames.cameras, 5.0, std::nullopt),
                       doctest::Contains("fix --near/--far"), Error);
  CHECK_THROWS_WITH_AS(eval::split_views(train::TrainedModel{}, "old.mnck", request, {}),
                       doctest::Contains("old.mnck does not record the data"), Error);
}

TEST_CASE("view cameras: a camera path file's frames, named by index, its folder by the file") {
  const auto dir = test::fresh_temp_dir("view-path");
  data::OrbitOptions orbit;
  orbit.frames = 4;
  orbit.intrinsics.width_px = orbit.intrinsics.height_px = 20;
  orbit.intrinsics.focal_x_px = orbit.intrinsics.focal_y_px = 25.0;
  const auto cameras = data::orbit_cameras(orbit);
  const std::string file = (dir / "flyby.json").string();
  data::write_camera_path(file, cameras, {"a.png", "b.png", "c.png", "d.png"});
  const eval::ViewFrames frames = eval::path_views(train::TrainedModel{}, file, {});
  REQUIRE(frames.cameras.size() == 4);
  CHECK(frames.stems[3] == "frame_0003");
  CHECK(frames.default_folder == "render_flyby");
  CHECK(frames.details["kind"] == "path");
  CHECK(frames.details["file"] == fs::absolute(file).lexically_normal().string());
  CHECK(frames.cameras[2].width_px == 20);
  CHECK(frames.cameras[2].camera_to_world[3] == doctest::Approx(cameras[2].camera_to_world[3]).epsilon(1e-9));
  fs::remove_all(dir);
}

// A camera path (a file, or the viewer's page) that leaves near/far out renders in the run's range: NDC's 0..1 on a
// run of cylinders (a forward-facing capture: Blender's 2..6 there sampled beyond the far plane, and the viewer's
// first view of such a run was 2 dB worse than the same camera's `render --split train`), the training cameras' own
// range on a capture that records one, the run's settings when it has them, an unbounded run's 0..1e6.
TEST_CASE("view cameras: a camera path without near/far takes the run's range: NDC, the capture's, or the settings'") {
  train::TrainedModel ndc;
  ndc.config.ray_shape = RayShape::cylinder;
  const data::CameraPathDefaults a = eval::camera_path_defaults(ndc, {});
  CHECK(a.near == 0.0);
  CHECK(a.far == 1.0);

  // A transforms.json capture whose cameras say near 0.5, far 8 (as an import writes them).
  const fs::path scene = test::render_temp("near-far-scene");
  fs::remove_all(scene);
  fs::create_directories(scene / "images");
  std::vector<float> rgb(4 * 4 * 3, 0.5f);
  io::write_png((scene / "images/0.png").string(), 4, 4, 3, rgb.data());
  io::Json frames = io::Json::array();
  for (int k = 0; k < 2; ++k) {
    frames.push_back({{"file_path", "images/0.png"},
                      {"transform_matrix", {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 4.0 + k}, {0, 0, 0, 1}}}});
  }
  io::write_json((scene / "transforms.json").string(), {{"fl_x", 5}, {"fl_y", 5}, {"cx", 2}, {"cy", 2}, {"w", 4},
                                                         {"h", 4}, {"near", 0.5}, {"far", 8}, {"frames", frames}});
  train::TrainedModel capture;
  capture.data_path = (scene / "transforms.json").string();
  const data::CameraPathDefaults b = eval::camera_path_defaults(capture, {});
  CHECK(b.near == 0.5);
  CHECK(b.far == 8.0);
  const auto cameras = data::parse_camera_path(
      R"({"frames": [{"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,4],[0,0,0,1]], "fl_x": 5, "w": 4, "h": 4}]})",
      "the page's camera", b);
  CHECK(cameras[0].near == 0.5);
  CHECK(cameras[0].far == 8.0);

  // The run's own settings win; without data or settings, Blender's range.
  capture.config.near = 1.0;
  capture.config.far = 3.0;
  const data::CameraPathDefaults c = eval::camera_path_defaults(capture, {});
  CHECK(c.near == 1.0);
  CHECK(c.far == 3.0);
  const data::CameraPathDefaults d = eval::camera_path_defaults(train::TrainedModel{}, {});
  CHECK(d.near == 2.0);
  CHECK(d.far == 6.0);
  // An unbounded run samples from the camera out to 1e6, as it trained (train::load_options), not between the
  // capture's bounds or Blender's, also when its data is gone.
  train::TrainedModel unbounded;
  unbounded.config.unbounded = true;
  const data::CameraPathDefaults e = eval::camera_path_defaults(unbounded, {});
  CHECK(e.near == 0.0);
  CHECK(e.far == 1e6);
  fs::remove_all(scene);
}
