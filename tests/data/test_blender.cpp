// Loading datasets written on the fly: the Blender format (compositing, cameras, splits, near/far) and the
// single-file transforms.json (fl_x/fl_y/cx/cy/w/h, global or per frame, camera_angle_x as fallback).
#include <doctest/doctest.h>

#include <cmath>

#include "data/dataset.hpp"
#include "data/intrinsics.hpp"
#include "support/data_fixtures.hpp"

using namespace mipnerf;
using test::contains;
using test::error_of;

namespace {

// The official Blender loader in float: code / 255, then rgb·α + bg·(1 − α).
float composited(int k, uint32_t x, uint32_t y, int c, float background) {
  const float value = test::test_code(k, x, y, c) / 255.0f, alpha = test::test_code(k, x, y, 3) / 255.0f;
  return value * alpha + background * (1.0f - alpha);
}

}  // namespace

TEST_CASE("blender: a small set loads with composited pixels, cameras from camera_angle_x and default near/far") {
  test::TempDir dir;
  const uint32_t w = 6, h = 4;
  test::write_blender_split(dir.path(), "train", 3, w, h, 0.9);
  test::write_blender_split(dir.path(), "val", 2, w, h, 0.9);
  for (auto background : {Background::white, Background::black, Background::none}) {
    data::LoadOptions options;
    options.background = background;
    const auto dataset = data::load_dataset(dir.path(), options);
    CHECK(dataset.format == data::DatasetFormat::blender);
    CHECK(dataset.split_names() == "train, val");
    const auto& train = dataset.split("train");
    REQUIRE(train.num_images() == 3);
    CHECK(train.num_pixels() == 3 * w * h);
    CHECK(train.pixel_offsets == std::vector<uint64_t>{0, 24, 48, 72});
    for (int k = 0; k < 3; ++k) {
      const auto& cam = train.cameras[k];
      CHECK(cam.width_px == w);
      CHECK(cam.height_px == h);
      // The Blender loader's focal = 0.5·w / tan(0.5·camera_angle_x), square pixels, centre w/2, h/2.
      CHECK(cam.focal_x_px == doctest::Approx(0.5 * w / std::tan(0.45)).epsilon(1e-12));
      CHECK(cam.focal_y_px == cam.focal_x_px);
      CHECK(cam.center_x_px == 3.0);
      CHECK(cam.center_y_px == 2.0);
      CHECK(cam.near == 2.0);
      CHECK(cam.far == 6.0);
      CHECK(cam.lossmult == 1.0);
      CHECK(train.scale_levels[k] == 0);
      // The pose is read back as written (the JSON holds doubles).
      for (int i = 0; i < 12; ++i) CHECK(cam.camera_to_world[i] == doctest::Approx(test::test_pose(k)[i]).epsilon(1e-15));
      for (uint32_t y = 0; y < h; ++y) {
        for (uint32_t x = 0; x < w; ++x) {
          for (int c = 0; c < 3; ++c) {
            const float got = train.image_rgb(k)[3 * (y * w + x) + c];
            const float want = background == Background::none
                                   ? test::test_code(k, x, y, c) / 255.0f
                                   : composited(k, x, y, c, background == Background::white ? 1.0f : 0.0f);
            REQUIRE(got == want);
          }
        }
      }
    }
  }
}

TEST_CASE("blender: requested splits, near/far from the file and overrides") {
  test::TempDir dir;
  test::write_blender_split(dir.path(), "train", 2, 4, 4);
  // near/far given in the file (as make-scene writes them).
  auto root = io::read_json(dir / "transforms_train.json");
  root["near"] = 0.5;
  root["far"] = 3.5;
  io::write_json(dir / "transforms_train.json", root);
  data::LoadOptions options;
  options.splits = {"train"};
  auto dataset = data::load_dataset(dir.path(), options);
  CHECK(dataset.splits.size() == 1);
  CHECK(dataset.split("train").cameras[0].near == 0.5);
  CHECK(dataset.split("train").cameras[0].far == 3.5);
  options.near = 1.0;
  options.far = 9.0;
  dataset = data::load_dataset(dir.path(), options);
  CHECK(dataset.split("train").cameras[1].near == 1.0);
  CHECK(dataset.split("train").cameras[1].far == 9.0);
  CHECK(contains(error_of([&] { dataset.split("test"); }), "no split 'test' (this dataset has: train)"));
  options.splits = {"train", "test"};
  CHECK(contains(error_of([&] { data::load_dataset(dir.path(), options); }),
                 "transforms_test.json: no such file (this dataset has the splits: train)"));
}

TEST_CASE("intrinsics: camera_angle_x and fl_x/cx describe the same camera identically") {
  const uint32_t w = 40, h = 30;
  const double angle = 0.6911112070083618;
  Camera from_angle, from_focal;
  data::resolve_intrinsics(data::read_intrinsics({{"camera_angle_x", angle}}, {}, "a"), w, h, from_angle, "a");
  const double focal = 0.5 * w / std::tan(0.5 * angle);
  const io::Json explicit_keys = {{"fl_x", focal}, {"fl_y", focal}, {"cx", w / 2.0}, {"cy", h / 2.0}, {"w", w}, {"h", h}};
  data::resolve_intrinsics(data::read_intrinsics(explicit_keys, {}, "b"), w, h, from_focal, "b");
  CHECK(from_angle.focal_x_px == from_focal.focal_x_px);
  CHECK(from_angle.focal_y_px == from_focal.focal_y_px);
  CHECK(from_angle.center_x_px == from_focal.center_x_px);
  CHECK(from_angle.center_y_px == from_focal.center_y_px);
  // The rays through every pixel agree too.
  for (double x : {0.5, 13.5, 39.5}) {
    for (double y : {0.5, 29.5}) {
      const auto a = camera_ray(from_angle, x, y), b = camera_ray(from_focal, x, y);
      for (int k = 0; k < 3; ++k) CHECK(a.direction_world[k] == b.direction_world[k]);
    }
  }
  // camera_angle_y gives fy when no fl_x is given; fl_y alone overrides.
  Camera both;
  data::resolve_intrinsics(data::read_intrinsics({{"camera_angle_x", 0.8}, {"camera_angle_y", 0.5}}, {}, "c"), w, h,
                           both, "c");
  CHECK(both.focal_y_px == doctest::Approx(0.5 * h / std::tan(0.25)).epsilon(1e-15));
}

TEST_CASE("transforms.json: global and per-frame intrinsics, holdout, and agreement with the Blender loader") {
  test::TempDir dir;
  const uint32_t w = 8, h = 6;
  test::write_blender_split(dir.path(), "train", 9, w, h, 0.7);
  const double focal = 0.5 * w / std::tan(0.35);
  auto blender = io::read_json(dir / "transforms_train.json");
  io::Json single = {{"fl_x", focal}, {"fl_y", focal}, {"cx", w / 2.0}, {"cy", h / 2.0}, {"w", w}, {"h", h},
                     {"k1", 0.0}, {"p1", 0.0}, {"frames", blender["frames"]}};
  // Frame 4 carries its own principal point and focal length (per-frame overrides the global values).
  single["frames"][4]["cx"] = 3.25;
  single["frames"][4]["fl_y"] = 9.0;
  io::write_json(dir / "transforms.json", single);

  data::LoadOptions options;
  const auto from_single = data::load_dataset(dir / "transforms.json", options);
  CHECK(from_single.format == data::DatasetFormat::transforms_json);
  // Every 8th frame (0 and 8) is held out as "test", and is the "val" split `train` scores too.
  REQUIRE(from_single.split_names() == "train, val, test");
  CHECK(from_single.split("train").num_images() == 7);
  CHECK(from_single.split("test").num_images() == 2);
  CHECK(from_single.split("val").files == from_single.split("test").files);
  options.splits = {"train"};
  const auto from_blender = data::load_dataset(dir.path(), options);  // the folder: transforms_train.json wins
  CHECK(from_blender.format == data::DatasetFormat::blender);
  const auto& a = from_blender.split("train");
  const auto& b = from_single.split("train");
  for (size_t i = 0; i < b.num_images(); ++i) {
    const size_t frame = i + 1 + (i >= 7 ? 1 : 0);  // train frames are 1..7
    CAPTURE(frame);
    const auto& ca = a.cameras[frame];
    const auto& cb = b.cameras[i];
    CHECK(cb.focal_x_px == doctest::Approx(ca.focal_x_px).epsilon(1e-15));
    CHECK(cb.center_y_px == ca.center_y_px);
    CHECK(cb.center_x_px == (frame == 4 ? 3.25 : ca.center_x_px));
    CHECK(cb.focal_y_px == (frame == 4 ? 9.0 : doctest::Approx(ca.focal_y_px).epsilon(1e-15)));
    CHECK(cb.camera_to_world == ca.camera_to_world);
    for (size_t p = 0; p < 3 * w * h; ++p) REQUIRE(b.image_rgb(i)[p] == a.image_rgb(frame)[p]);
  }
  options.holdout_every = 0;
  options.splits = {};
  CHECK(data::load_dataset(dir / "transforms.json", options).split_names() == "train");
}
