// A transforms.json of forward-facing photos (what `dataset from-photos` and `import-colmap` write for a capture
// behind a lens, which LLFF cannot hold) trains as an LLFF capture does: NDC rays through cylinders, in the world
// LLFF's loader makes (the nearest depth at 4/3, recentred on the average camera), with the official spiral; and when
// the file cannot give NDC what it needs (its depths, one projection), it stays on world rays and says why.
#include <doctest/doctest.h>

#include <cmath>

#include "data/dataset.hpp"
#include "data/formats/formats.hpp"
#include "data/formats/llff_capture.hpp"
#include "data/synthetic/forward_facing.hpp"
#include "support/data_fixtures.hpp"
#include "support/temp_scene.hpp"
#include "train/model.hpp"
#include "train/scene_effects.hpp"

using namespace mipnerf;

namespace {

double largest_difference(const data::Matrix34& a, const data::Matrix34& b) {
  double worst = 0.0;
  for (size_t k = 0; k < a.size(); ++k) worst = std::max(worst, std::abs(a[k] - b[k]));
  return worst;
}

// A rotation of the world about (1, 2, 3)/√14 by 0.6 rad: another tool's axes.
data::Matrix34 world_rotation() {
  const double n = std::sqrt(14.0), x = 1 / n, y = 2 / n, z = 3 / n, c = std::cos(0.6), s = std::sin(0.6);
  return {c + x * x * (1 - c),     x * y * (1 - c) - z * s, x * z * (1 - c) + y * s, 0,
          y * x * (1 - c) + z * s, c + y * y * (1 - c),     y * z * (1 - c) - x * s, 0,
          z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c),     0};
}

struct Capture {
  std::string dir, file;
  std::vector<Camera> llff_ndc;       // the LLFF loader's NDC cameras of the same photos
  std::vector<Camera> llff_spiral;    // its official spiral
};

// The forward-facing procedural capture (LLFF layout), and its photos again as a transforms.json beside them in a world
// rotated, moved and scaled by 4 (as a COLMAP import leaves it), near/far the LLFF capture's depth range in those units.
// `with_depths` false leaves near/far out; `other_focal_frame` ≥ 0 gives that frame another focal length.
Capture forward_capture(const std::string& name, bool with_depths = true, int other_focal_frame = -1) {
  Capture capture;
  capture.dir = test::fresh_temp_dir(name).string();
  data::ForwardFacingOptions scene;
  scene.width_px = 32;
  scene.views_x = 3;
  scene.views_y = 3;
  scene.factor = 1;
  scene.samples_per_axis = 1;
  scene.threads = 2;
  data::write_forward_facing_scene(capture.dir, scene);
  data::LoadOptions llff_options;  // the official LLFF: NDC
  llff_options.holdout_every = 8;
  capture.llff_ndc = test::every_camera_in_file_order(data::load_dataset(capture.dir, llff_options));
  const data::LlffCapture llff = data::read_llff(capture.dir, llff_options);
  capture.llff_spiral = data::llff_render_path(llff, llff_options, 6);
  double nearest = llff.bounds[0][0], farthest = llff.bounds[0][1];
  for (const auto& b : llff.bounds) {
    nearest = std::min(nearest, b[0]);
    farthest = std::max(farthest, b[1]);
  }

  const double scale = 4.0;
  const data::Matrix34 rotation = world_rotation();
  const Vec3 offset{30.0, -12.0, 5.0};
  io::Json frames = io::Json::array();
  for (size_t i = 0; i < llff.camera_to_world.size(); ++i) {
    const data::Matrix34& p = llff.camera_to_world[i];
    data::Matrix34 moved{};
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) {
        double v = 0.0;
        for (int k = 0; k < 3; ++k) v += rotation[4 * r + k] * p[4 * k + c];
        moved[4 * r + c] = c == 3 ? scale * v + offset[r] : v;
      }
    }
    io::Json frame = {{"file_path", std::filesystem::relative(llff.image_files[i], capture.dir).string()},
                      {"transform_matrix", data::pose_to_json(moved)},
                      {"fl_x", llff.focal_px * (static_cast<int>(i) == other_focal_frame ? 1.5 : 1.0)},
                      {"fl_y", llff.focal_px},
                      {"w", llff.width_px},
                      {"h", llff.height_px}};
    frames.push_back(frame);
  }
  io::Json root = {{"frames", frames}};
  if (with_depths) {
    root["near"] = scale * nearest;
    root["far"] = scale * farthest;
  }
  capture.file = capture.dir + "/transforms.json";
  io::write_json(capture.file, root);
  return capture;
}

}  // namespace

TEST_CASE("transforms.json: forward-facing photos train in NDC, in the world and with the spiral LLFF's loader gives") {
  const Capture capture = forward_capture("transforms-forward");
  const auto traits = data::scene_traits(capture.file, data::LoadOptions{});
  CHECK(traits.format == data::DatasetFormat::transforms_json);
  CHECK(traits.forward_facing);
  CHECK(!traits.all_around);
  CHECK(traits.ndc_blocker.empty());
  // The effects of a forward-facing LLFF capture (but spherify, an LLFF option), for mip-NeRF and Zip-NeRF alike.
  const train::SceneEffects mip = train::scene_effects(capture.file, 1);
  CHECK(mip.settings == std::map<std::string, std::string>{{"ray_shape", "cylinder"},
                                                           {"background", "black"},
                                                           {"unit_viewdirs", "false"},
                                                           {"density_noise", "1"}});
  CHECK(mip.summary == "transforms.json of forward-facing photos → NDC rays, cylinders, black background, raw view "
                       "directions, density noise 1");
  CHECK(train::scene_effects(capture.file, 1, train::ModelFamily::zipnerf).zipnerf_settings.empty());
  CHECK(train::scene_effects(capture.file, 1).mipnerf_settings.empty());
  std::string line;
  const train::TrainConfig config = train::resolve_config("quick", "mipnerf", train::with_scene_effects(mip, {}, line));
  REQUIRE(config.ray_shape == RayShape::cylinder);

  // What the run loads: every camera where the LLFF loader puts the same photo's (the world's rotation, offset and
  // unit undone by the nearest depth and the recentring), near 0 and far 1.
  const data::LoadOptions options = train::load_options(config, capture.file, {}, 1);
  CHECK(options.forward_facing_ndc);
  const std::vector<Camera> cameras = test::every_camera_in_file_order(data::load_dataset(capture.file, options));
  REQUIRE(cameras.size() == capture.llff_ndc.size());
  double worst = 0.0;
  for (size_t i = 0; i < cameras.size(); ++i) {
    worst = std::max(worst, largest_difference(cameras[i].camera_to_world, capture.llff_ndc[i].camera_to_world));
    CHECK(cameras[i].near == 0.0);
    CHECK(cameras[i].far == 1.0);
    CHECK(cameras[i].focal_x_px == doctest::Approx(capture.llff_ndc[i].focal_x_px).epsilon(1e-12));
    CHECK(cameras[i].width_px == capture.llff_ndc[i].width_px);
  }
  MESSAGE("largest pose difference from the LLFF loader's: " << worst);
  CHECK(worst < 1e-9);

  // `render --path spiral`: the LLFF spiral of the same capture.
  const data::FormatRenderPath spiral =
      data::format_reader(data::DatasetFormat::transforms_json).render_path(capture.file, options, 6);
  REQUIRE(spiral.cameras.size() == capture.llff_spiral.size());
  worst = 0.0;
  for (size_t k = 0; k < spiral.cameras.size(); ++k) {
    worst = std::max(worst, largest_difference(spiral.cameras[k].camera_to_world, capture.llff_spiral[k].camera_to_world));
    CHECK(spiral.cameras[k].focal_x_px == doctest::Approx(capture.llff_spiral[k].focal_x_px).epsilon(1e-12));
    CHECK(spiral.cameras[k].width_px == capture.llff_spiral[k].width_px);
    CHECK(spiral.cameras[k].near == 0.0);
    CHECK(spiral.cameras[k].far == 1.0);
  }
  MESSAGE("largest spiral pose difference from the LLFF path's: " << worst);
  CHECK(worst < 1e-9);
  CHECK(spiral.kind == "transforms.json spiral");
}

TEST_CASE("transforms.json: forward-facing photos NDC cannot hold stay on world rays, saying why, and NDC refuses them") {
  SUBCASE("no near/far in the file") {
    const Capture capture = forward_capture("transforms-forward-no-depths", /*with_depths=*/false);
    const auto traits = data::scene_traits(capture.file, data::LoadOptions{});
    CHECK(traits.forward_facing);
    CHECK(traits.ndc_blocker == "the file gives no near/far");
    const train::SceneEffects mip = train::scene_effects(capture.file, 1);
    CHECK(mip.settings.at("ray_shape") == "cone");
    CHECK(mip.summary == "transforms.json without alpha (photos) → cones, black background (forward-facing, but not "
                         "NDC: the file gives no near/far)");
    data::LoadOptions ndc;
    ndc.forward_facing_ndc = true;
    CHECK_THROWS_WITH(data::load_dataset(capture.file, ndc),
                      doctest::Contains("transforms.json: NDC rays (ray_shape = cylinder, for a forward-facing capture) "
                                        "need the capture's nearest depth, and this file gives no near/far"));
  }
  SUBCASE("a frame of another focal length") {
    const Capture capture = forward_capture("transforms-forward-two-cameras", /*with_depths=*/true, 3);
    const auto traits = data::scene_traits(capture.file, data::LoadOptions{});
    CHECK(traits.ndc_blocker == "its frames differ in focal length, principal point or image size");
    CHECK(train::scene_effects(capture.file, 1).settings.at("ray_shape") == "cone");
    data::LoadOptions ndc;
    ndc.forward_facing_ndc = true;
    CHECK_THROWS_WITH(data::load_dataset(capture.file, ndc),
                      doctest::Contains("transforms.json: frames[3]: its focal length or principal point, per image "
                                        "size, differs from"));
  }
  SUBCASE("the spiral of a run on world rays") {
    const Capture capture = forward_capture("transforms-forward-cones");
    data::LoadOptions cones;
    CHECK_THROWS_WITH(data::format_reader(data::DatasetFormat::transforms_json).render_path(capture.file, cones, 4),
                      doctest::Contains("this run casts world rays: use --path orbit"));
  }
}
