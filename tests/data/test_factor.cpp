// LoadOptions::factor (the official Config.factor): box-downsampled images with matching intrinsics.
#include <doctest/doctest.h>

#include <cmath>

#include "core/error.hpp"
#include "data/dataset.hpp"
#include "support/data_fixtures.hpp"
#include "train/model.hpp"

using namespace mipnerf;

namespace {

// An opaque width x height Blender split (alpha 255 everywhere, so compositing changes nothing and the expected
// downsampled pixel is exactly the mean of its block).
void write_opaque_split(const std::string& dir, uint32_t width = 8, uint32_t height = 8) {
  io::Json frames = io::Json::array();
  for (int k = 0; k < 2; ++k) {
    std::vector<uint8_t> rgba(static_cast<size_t>(width) * height * 4);
    for (size_t i = 0; i < static_cast<size_t>(width) * height; ++i) {
      for (int c = 0; c < 3; ++c) rgba[4 * i + c] = static_cast<uint8_t>((37 * i + 91 * c + 13 * k) % 256);
      rgba[4 * i + 3] = 255;
    }
    io::write_png8(dir + "/train/r_" + std::to_string(k) + ".png", width, height, 4, rgba.data());
    frames.push_back({{"file_path", "./train/r_" + std::to_string(k)},
                      {"transform_matrix", data::pose_to_json(test::test_pose(k))}});
  }
  io::write_json(dir + "/transforms_train.json", {{"camera_angle_x", 0.69}, {"frames", frames}});
}

// Every pixel of `small` (width x height, RGB) is the mean of its factor x factor block of `big` (big_width wide, RGB):
// float32 averages of k/255 values, within a few float ulps of the double mean.
void check_block_means(const float* big, uint32_t big_width, const float* small, uint32_t width, uint32_t height,
                       uint32_t factor) {
  for (uint32_t y = 0; y < height; ++y) {
    for (uint32_t x = 0; x < width; ++x) {
      for (int ch = 0; ch < 3; ++ch) {
        double mean = 0;
        for (uint32_t dy = 0; dy < factor; ++dy)
          for (uint32_t dx = 0; dx < factor; ++dx)
            mean += big[3 * ((factor * y + dy) * big_width + factor * x + dx) + ch] / double(factor * factor);
        CHECK(std::abs(mean - small[3 * (y * width + x) + ch]) < 1e-6);
      }
    }
  }
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
    check_block_means(full.image_rgb(c), 8, half.image_rgb(c), 4, 4, 2);
  }
  data::LoadOptions bad;
  bad.factor = 3;
  CHECK_THROWS_WITH_AS(data::load_dataset(dir.path(), bad), doctest::Contains("power of two"), Error);
  bad.factor = 16;
  CHECK_THROWS_WITH_AS(data::load_dataset(dir.path(), bad), doctest::Contains("smaller than factor 16"), Error);
}

// Issue 45: 800x533 photos at factor 4 were refused ("not divisible by factor 4"). Now the right and bottom edges the
// factor does not divide are dropped first, so every kept pixel is still the mean of its own f x f block and the
// intrinsics are the full image's divided by f, exactly; the loader says what it dropped.
TEST_CASE("factor: a size the factor does not divide is cropped at its right and bottom edges, the camera exact") {
  test::TempDir dir;
  write_opaque_split(dir.path(), 11, 7);  // factor 4: 8x4 kept, 2x1 trained
  const auto full = data::load_dataset(dir.path(), {}).split("train");
  data::LoadOptions quarter_options;
  quarter_options.factor = 4;
  std::vector<std::string> warnings;
  quarter_options.log = [&](LogLevel level, const std::string& message) {
    if (level == LogLevel::warning) warnings.push_back(message);
  };
  const auto quarter = data::load_dataset(dir.path(), quarter_options).split("train");
  REQUIRE(warnings.size() == 1);  // once per split, not once per image
  CHECK(warnings[0].find("11x7 is not divisible by factor 4: its last 3 columns and 3 rows are dropped") !=
        std::string::npos);
  CHECK(warnings[0].find("trains at 2x1") != std::string::npos);
  REQUIRE(quarter.num_images() == full.num_images());
  for (size_t c = 0; c < full.num_images(); ++c) {
    const auto& a = full.cameras[c];
    const auto& b = quarter.cameras[c];
    CHECK(b.width_px == 2);
    CHECK(b.height_px == 1);
    // The principal point and focal length of the full image, in quarter-size pixels: unchanged by the crop.
    CHECK(b.focal_x_px == doctest::Approx(a.focal_x_px / 4).epsilon(1e-12));
    CHECK(b.focal_y_px == doctest::Approx(a.focal_y_px / 4).epsilon(1e-12));
    CHECK(b.center_x_px == doctest::Approx(a.center_x_px / 4).epsilon(1e-12));
    CHECK(b.center_y_px == doctest::Approx(a.center_y_px / 4).epsilon(1e-12));
    check_block_means(full.image_rgb(c), 11, quarter.image_rgb(c), 2, 1, 4);
  }
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
