// LoadOptions::factor (the official Config.factor): box-downsampled images with matching intrinsics.
#include <doctest/doctest.h>

#include <cmath>

#include "core/error.hpp"
#include "data/dataset.hpp"
#include "support/data_fixtures.hpp"
#include "train/model.hpp"

using namespace mipnerf;

namespace {

// An opaque 8x8 Blender split (alpha 255 everywhere, so compositing changes nothing and the expected
// half-resolution pixel is exactly the mean of its 2x2 block).
void write_opaque_split(const std::string& dir) {
  io::Json frames = io::Json::array();
  for (int k = 0; k < 2; ++k) {
    std::vector<uint8_t> rgba(8 * 8 * 4);
    for (size_t i = 0; i < 64; ++i) {
      for (int c = 0; c < 3; ++c) rgba[4 * i + c] = static_cast<uint8_t>((37 * i + 91 * c + 13 * k) % 256);
      rgba[4 * i + 3] = 255;
    }
    io::write_png8(dir + "/train/r_" + std::to_string(k) + ".png", 8, 8, 4, rgba.data());
    frames.push_back({{"file_path", "./train/r_" + std::to_string(k)},
                      {"transform_matrix", data::pose_to_json(test::test_pose(k))}});
  }
  io::write_json(dir + "/transforms_train.json", {{"camera_angle_x", 0.69}, {"frames", frames}});
}

}  // namespace

TEST_CASE("factor: images are box-downsampled and the camera follows, lossmult stays") {
  test::TempDir dir;
  write_opaque_split(dir.path());
  data::LoadOptions full_options, half_options;
  half_options.factor = 2;
  const auto full = data::load_dataset(dir.path(), full_options).split("train");
  const auto half = data::load_dataset(dir.path(), half_options).split("train");
  REQUIRE(half.num_images() == full.num_images());
  for (size_t c = 0; c < full.num_images(); ++c) {
    const auto& a = full.cameras[c];
    const auto& b = half.cameras[c];
    CHECK(b.width_px == 4);
    CHECK(b.height_px == 4);
    CHECK(b.focal_x_px == doctest::Approx(a.focal_x_px / 2).epsilon(1e-12));
    CHECK(b.center_x_px == doctest::Approx(a.center_x_px / 2).epsilon(1e-12));
    CHECK(b.lossmult == a.lossmult);
    const float* big = full.image_rgb(c);
    const float* small = half.image_rgb(c);
    for (uint32_t y = 0; y < 4; ++y) {
      for (uint32_t x = 0; x < 4; ++x) {
        for (int ch = 0; ch < 3; ++ch) {
          double mean = 0;
          for (int dy = 0; dy < 2; ++dy)
            for (int dx = 0; dx < 2; ++dx) mean += big[3 * ((2 * y + dy) * 8 + 2 * x + dx) + ch] / 4.0;
          // Float32 averages of four k/255 values: within a few float ulps of the double mean.
          CHECK(std::abs(mean - small[3 * (y * 4 + x) + ch]) < 1e-6);
        }
      }
    }
  }
  data::LoadOptions bad;
  bad.factor = 3;
  CHECK_THROWS_WITH_AS(data::load_dataset(dir.path(), bad), doctest::Contains("power of two"), Error);
  bad.factor = 16;
  CHECK_THROWS_WITH_AS(data::load_dataset(dir.path(), bad), doctest::Contains("not divisible by factor 16"), Error);
}

TEST_CASE("factor: the training setting reaches the loader, with the multiscale pyramid on top") {
  test::TempDir dir;
  write_opaque_split(dir.path());
  train::TrainConfig config;
  config.factor = 2;
  config.multiscale = true;
  const auto options = train::load_options(config, dir.path(), {"train"});
  CHECK(options.factor == 2);
  CHECK(options.scales == 4);
  config.multiscale = false;
  CHECK(train::load_options(config, dir.path(), {"train"}).scales == 1);
  // 8x8 at factor 2 is 4x4: two more scales fit (4, 2), four do not.
  CHECK_THROWS_WITH_AS(data::load_dataset(dir.path(), options), doctest::Contains("not divisible by 8"), Error);
}
