// Real captures end to end: a COLMAP model made from the procedural scene's cameras and surface points, in a world
// moved, turned and scaled away from ours, imports with the cameras recovered and trains.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "data/import/colmap_import.hpp"
#include "data/dataset.hpp"
#include "data/synthetic/procedural.hpp"
#include "support/colmap_writer.hpp"
#include "support/test_context.hpp"
#include "support/train_fixtures.hpp"
#include "train/trainer.hpp"

using namespace mipnerf;
namespace fs = std::filesystem;

namespace {

// world' = kScale · Rz(kTurn) · world + kShift: a COLMAP world with its own origin, orientation and unit.
constexpr double kScale = 2.5, kTurn = 0.7;
constexpr Vec3 kShift{300.0, -120.0, 45.0};

Vec3 turn(const Vec3& v) {
  return {std::cos(kTurn) * v[0] - std::sin(kTurn) * v[1], std::sin(kTurn) * v[0] + std::cos(kTurn) * v[1], v[2]};
}

Vec3 to_colmap_world(const Vec3& x) {
  const Vec3 r = turn(x);
  return {kScale * r[0] + kShift[0], kScale * r[1] + kShift[1], kScale * r[2] + kShift[2]};
}

data::Matrix34 to_colmap_world(const data::Matrix34& pose) {
  data::Matrix34 moved{};
  for (int col = 0; col < 3; ++col) {
    const Vec3 axis = turn({pose[col], pose[4 + col], pose[8 + col]});
    for (int row = 0; row < 3; ++row) moved[row * 4 + col] = axis[row];
  }
  const Vec3 centre = to_colmap_world(Vec3{pose[3], pose[7], pose[11]});
  for (int row = 0; row < 3; ++row) moved[row * 4 + 3] = centre[row];
  return moved;
}

}  // namespace

TEST_CASE("train: a COLMAP model of the procedural scene in a moved, turned, scaled world imports and trains") {
  const std::string scene = test::small_scene();
  data::LoadOptions train_only;
  train_only.splits = {"train"};
  const data::Split blender = data::load_dataset(scene, train_only).split("train");
  const Camera& first = blender.cameras[0];

  // The model: one PINHOLE camera, the train views, and points where rays through every 4th pixel hit the scene,
  // each observed by the views that have it in front and inside the image (sparse models do not test occlusion
  // either way: a track lists where the point was matched).
  test::ColmapTestModel model;
  model.cameras = {{1,
                    "PINHOLE",
                    1,
                    first.width_px,
                    first.height_px,
                    {first.focal_x_px, first.focal_y_px, first.center_x_px, first.center_y_px}}};
  for (size_t k = 0; k < blender.num_images(); ++k) {
    model.images.push_back(test::colmap_image(static_cast<uint32_t>(k + 1), 1, fs::path(blender.files[k]).filename(),
                                              to_colmap_world(blender.cameras[k].camera_to_world)));
  }
  double depth_min = 1e30, depth_max = 0.0;
  for (size_t k = 0; k < blender.num_images(); k += 3) {
    for (uint32_t y = 2; y < first.height_px; y += 4) {
      for (uint32_t x = 2; x < first.width_px; x += 4) {
        const Ray ray = camera_ray(blender.cameras[k], x + 0.5, y + 0.5);
        const data::SceneHit hit = data::trace_procedural(ray);
        if (!hit.hit) continue;
        Vec3 point{};
        for (int a = 0; a < 3; ++a) point[a] = ray.origin_world[a] + hit.t * ray.direction_world[a];
        test::ColmapTestPoint colmap_point{model.points.size() + 1, to_colmap_world(point), {}};
        for (const auto& image : model.images) {
          const Vec3 c = test::to_colmap_camera(image, colmap_point.xyz);
          const double u = first.focal_x_px * c[0] / c[2] + first.center_x_px;
          const double v = first.focal_y_px * c[1] / c[2] + first.center_y_px;
          if (c[2] <= 0 || u < 0 || v < 0 || u > first.width_px || v > first.height_px) continue;
          colmap_point.image_ids.push_back(image.id);
          depth_min = std::min(depth_min, c[2] / kScale);
          depth_max = std::max(depth_max, c[2] / kScale);
        }
        model.points.push_back(colmap_point);
      }
    }
  }
  REQUIRE(model.points.size() > 100);
  const fs::path dir = test::fresh_temp_dir("colmap-train");
  test::write_colmap_model((dir / "sparse").string(), model, true);
  const auto imported =
      data::import_colmap((dir / "sparse").string(), (fs::path(scene) / "train").string(), (dir / "out").string());

  // The cameras look at the origin of our world, so the centre is its image in COLMAP's, and the scale undoes kScale
  // (the procedural cameras are 4 from the origin): the imported world is ours turned by Rz.
  CHECK(imported.centre_rule == "look-at");
  for (int a = 0; a < 3; ++a) CHECK(imported.centre[a] == doctest::Approx(kShift[a]).epsilon(1e-9));
  CHECK(imported.scale == doctest::Approx(1.0 / kScale).epsilon(1e-9));
  CHECK(imported.near < depth_min);
  CHECK(imported.near > 0.5 * depth_min);
  CHECK(imported.far > depth_max);
  CHECK(imported.far < 2.0 * depth_max);
  data::LoadOptions all;
  all.holdout_every = 0;
  const data::Split split = data::load_dataset(imported.transforms_path, all).split("train");
  REQUIRE(split.num_images() == blender.num_images());
  for (size_t i = 0; i < split.num_images(); ++i) {
    // The imported frame's file is a link in the dataset's images/ folder to the photo it names.
    const auto original = std::find_if(blender.files.begin(), blender.files.end(), [&](const std::string& file) {
      return fs::canonical(file) == fs::canonical(split.files[i]);
    });
    REQUIRE(original != blender.files.end());
    const Camera& expected = blender.cameras[original - blender.files.begin()];
    CAPTURE(split.files[i]);
    const auto& m = split.cameras[i].camera_to_world;
    for (int col = 0; col < 4; ++col) {
      const Vec3 column =
          turn({expected.camera_to_world[col], expected.camera_to_world[4 + col], expected.camera_to_world[8 + col]});
      for (int row = 0; row < 3; ++row)
        CHECK(m[row * 4 + col] == doctest::Approx(column[row]).scale(1.0).epsilon(1e-9));
    }
    CHECK(split.cameras[i].focal_x_px == expected.focal_x_px);
    for (size_t p = 0; p < 3 * 32 * 32; p += 97)
      REQUIRE(split.image_rgb(i)[p] == blender.image_rgb(original - blender.files.begin())[p]);
  }

  // What `mipnerf-cl train --data OUT/transforms.json --preset tiny --steps 20` runs.
  const std::string run = test::fresh_run_dir("colmap");
  train::Trainer trainer(test::test_context(),
                         train::resolve_config("tiny", "mipnerf", {{"steps", "20"}, {"log_every", "1"}}),
                         imported.transforms_path, run, false);
  const auto result = trainer.run();
  CHECK(result.last_step == 20);
  CHECK(result.skipped_steps == 0);
  CHECK(std::isfinite(result.final_psnr));
  MESSAGE("batch PSNR after 20 steps on the imported scene: " << result.final_psnr << " dB");
  fs::remove_all(run);
  fs::remove_all(dir);
}
