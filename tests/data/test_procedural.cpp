// The built-in procedural scene: analytic hits, anti-aliased supersampling, deterministic output, and the
// written Blender + multiscale folders loading with sensible cameras (the tests' fixture).
#include <doctest/doctest.h>

#include <cmath>
#include <fstream>
#include <iterator>

#include "data/dataset.hpp"
#include "data/inspect.hpp"
#include "data/synthetic/procedural.hpp"
#include "support/data_fixtures.hpp"

using namespace mipnerf;

namespace {

data::SceneOptions small_scene(uint64_t seed = 7) {
  data::SceneOptions options;
  options.size_px = 16;
  options.train_views = 5;
  options.val_views = 2;
  options.test_views = 3;
  options.scales = 2;
  options.samples_per_axis = 3;
  options.seed = seed;
  options.threads = 2;
  return options;
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

double mean_abs_difference(const data::RgbaImage& a, const data::RgbaImage& b) {
  double sum = 0;
  for (size_t i = 0; i < a.rgba.size(); ++i) sum += std::abs(a.rgba[i] - b.rgba[i]);
  return sum / a.rgba.size();
}

}  // namespace

TEST_CASE("procedural: rays hit the analytic surfaces where geometry says") {
  // Straight down onto the sphere (centre z 0.25, radius 0.55): its top is at z = 0.8, t = 3.2.
  auto hit = data::trace_procedural({{0.0, 0.0, 4.0}, {0.0, 0.0, -1.0}});
  CHECK(hit.hit);
  CHECK(hit.t == doctest::Approx(3.2).epsilon(1e-12));
  // The direction is not normalised: t scales inversely with its length.
  hit = data::trace_procedural({{0.0, 0.0, 4.0}, {0.0, 0.0, -2.0}});
  CHECK(hit.t == doctest::Approx(1.6).epsilon(1e-12));
  // Onto the top face of the striped box at (0.8, −0.55, −0.2), half height 0.35: z = 0.15.
  hit = data::trace_procedural({{0.8, -0.55, 4.0}, {0.0, 0.0, -1.0}});
  CHECK(hit.hit);
  CHECK(hit.t == doctest::Approx(3.85).epsilon(1e-12));
  // Away from everything.
  CHECK_FALSE(data::trace_procedural({{0.0, 0.0, 4.0}, {0.0, 0.0, 1.0}}).hit);
  CHECK_FALSE(data::trace_procedural({{5.0, 5.0, 4.0}, {0.0, 0.0, -1.0}}).hit);
  // Shaded colours stay in [0, 1].
  for (double x = -1.2; x <= 1.2; x += 0.1) {
    const auto h = data::trace_procedural({{x, 0.3 * x, 4.0}, {0.0, 0.0, -1.0}});
    for (double c : h.rgb) CHECK((c >= 0.0 && c <= 1.0));
  }
}

TEST_CASE("procedural: jittered supersampling converges, so the ground truth is anti-aliased") {
  auto options = small_scene();
  options.size_px = 32;
  const auto camera = data::procedural_cameras("val", options)[0];
  auto render = [&](uint32_t per_axis) {
    options.samples_per_axis = per_axis;
    return data::render_procedural(camera, options, 3);
  };
  const auto one = render(1), few = render(4), many = render(16);
  // The scene shows both objects and background.
  size_t empty = 0, full = 0, partial_one = 0, partial_few = 0;
  for (size_t p = 0; p < 32 * 32; ++p) {
    empty += many.rgba[4 * p + 3] == 0.0f;
    full += many.rgba[4 * p + 3] == 1.0f;
    partial_one += one.rgba[4 * p + 3] != 0.0f && one.rgba[4 * p + 3] != 1.0f;
    partial_few += few.rgba[4 * p + 3] != 0.0f && few.rgba[4 * p + 3] != 1.0f;
  }
  CHECK(empty > 100);
  CHECK(full > 100);
  CHECK(partial_one == 0);  // one ray per pixel: every silhouette pixel is all-or-nothing (aliased)
  CHECK(partial_few > 20);  // 16 rays: silhouette pixels get fractional coverage
  // Against 256 rays per pixel, 16 are far closer than 1 (stratified jitter: the error at edges falls faster
  // than 1/√n). Measured here: 0.065 for 1 ray, 0.012 for 16; the bounds leave room for other seeds.
  const double error_one = mean_abs_difference(one, many), error_few = mean_abs_difference(few, many);
  MESSAGE("mean abs error against 256 rays: 1 ray " << error_one << ", 16 rays " << error_few);
  CHECK(error_few < 0.5 * error_one);
  CHECK(error_few < 0.02);
}

TEST_CASE("procedural: the written scene loads as Blender and multiscale with cameras around the origin") {
  test::TempDir dir;
  const auto options = small_scene();
  data::write_procedural_scene(dir.path(), options);
  const auto dataset = data::load_dataset(dir.path());
  CHECK(dataset.format == data::DatasetFormat::blender);
  REQUIRE(dataset.split_names() == "train, val, test");
  const size_t counts[3] = {5, 2, 3};
  for (int s = 0; s < 3; ++s) {
    const auto& split = dataset.splits[s];
    CHECK(split.num_images() == counts[s]);
    const auto summary = data::summarize(split);
    REQUIRE(summary.look_at.has_value());
    for (double v : *summary.look_at) CHECK(std::abs(v) < 1e-6);  // every camera looks at the origin
    CHECK(summary.cameras_facing == counts[s]);
    CHECK(summary.radius_min == doctest::Approx(4.0).epsilon(1e-12));
    CHECK(summary.radius_max == doctest::Approx(4.0).epsilon(1e-12));
    CHECK(summary.center_min[2] > 0.0);  // the upper hemisphere
    CHECK(summary.near_min == 2.0);
    CHECK(summary.far_max == 6.0);
    for (const auto& camera : split.cameras) {
      CHECK(camera.width_px == 16);
      CHECK(camera.focal_x_px == doctest::Approx(8.0 / std::tan(0.5 * options.camera_angle_x)).epsilon(1e-12));
    }
  }
  // The cameras are exactly procedural_cameras' (the file stores doubles).
  const auto train_cameras = data::procedural_cameras("train", options);
  for (size_t v = 0; v < 5; ++v) {
    for (int i = 0; i < 12; ++i) {
      CHECK(dataset.split("train").cameras[v].camera_to_world[i] ==
            doctest::Approx(train_cameras[v].camera_to_world[i]).epsilon(1e-15));
    }
  }
  const auto multiscale = data::load_dataset(dir / "multiscale");
  CHECK(multiscale.format == data::DatasetFormat::multiscale_blender);
  const auto& train = multiscale.split("train");
  CHECK(train.num_images() == 10);
  CHECK(train.num_scales() == 2);
  CHECK(train.cameras[1].width_px == 8);
  CHECK(train.cameras[1].lossmult == 4.0);
}

TEST_CASE("procedural: the same seed writes the same bytes, another seed other cameras") {
  test::TempDir a, b, c;
  auto options = small_scene(11);
  options.scales = 1;
  options.threads = 1;
  data::write_procedural_scene(a.path(), options);
  options.threads = 2;  // the thread count must not change anything
  data::write_procedural_scene(b.path(), options);
  for (const char* file : {"transforms_train.json", "transforms_test.json", "train/r_0.png", "train/r_4.png",
                           "val/r_1.png", "test/r_2.png"}) {
    CAPTURE(file);
    const std::string bytes = file_bytes(a / file);
    CHECK(!bytes.empty());
    CHECK(bytes == file_bytes(b / file));
  }
  options.seed = 12;
  data::write_procedural_scene(c.path(), options);
  CHECK(file_bytes(a / "transforms_train.json") != file_bytes(c / "transforms_train.json"));
  CHECK(file_bytes(a / "train/r_0.png") != file_bytes(c / "train/r_0.png"));
}

TEST_CASE("procedural: bad options are refused with what to change") {
  auto options = small_scene();
  options.size_px = 20;
  options.scales = 4;
  CHECK(test::error_of([&] { data::validate(options); }) ==
        "make-scene: --size 20 is not divisible by 8 for 4 scales; use a multiple of 8");
  options = small_scene();
  options.train_views = 0;
  CHECK(test::error_of([&] { data::validate(options); }) == "make-scene: --views must be at least 1");
}
