// The multiscale Blender pyramid (the paper's make_multiscale): the 2×2 box filter on straight RGBA against a
// hand-computed case, loss multipliers 1, 4, 16, 64, scaled intrinsics (so the cone radius follows the pixel
// size), and the on-disk builder against the on-the-fly one.
#include <doctest/doctest.h>

#include <cmath>

#include "data/dataset.hpp"
#include "data/image.hpp"
#include "data/multiscale.hpp"
#include "support/data_fixtures.hpp"

using namespace mipnerf;
using test::contains;
using test::error_of;

TEST_CASE("multiscale: the box filter averages straight RGBA, alpha included, then compositing follows") {
  // A 4×2 image: its left 2×2 block holds red (opaque), blue (transparent), green (opaque), white (transparent).
  data::RgbaImage image{4, 2, {
      1, 0, 0, 1,   0, 0, 1, 0,   0.2f, 0.4f, 0.6f, 0.8f,   0.2f, 0.4f, 0.6f, 0.8f,
      0, 1, 0, 1,   1, 1, 1, 0,   0.2f, 0.4f, 0.6f, 0.8f,   0.6f, 0.0f, 0.2f, 0.4f}};
  const auto half = data::downsample2(image);
  REQUIRE(half.width == 2);
  REQUIRE(half.height == 1);
  // Hand-computed means of each 2×2 block, channel by channel.
  const float expected[8] = {0.5f, 0.5f, 0.5f, 0.5f, 0.3f, 0.3f, 0.5f, 0.7f};
  for (int i = 0; i < 8; ++i) CHECK(half.rgba[i] == doctest::Approx(expected[i]).epsilon(1e-7));
  float rgb[6];
  data::composite(half, Background::white, rgb);
  // Official semantics (convert_blender_data.py averages the stored RGBA; the loader composites after):
  // 0.5·0.5 + (1 − 0.5) = 0.75 in every channel. Compositing each pixel first would give (0.75, 0.75, 0.5):
  // the two differ at edges between opaque and transparent pixels, and we follow the official data.
  for (int c = 0; c < 3; ++c) CHECK(rgb[c] == doctest::Approx(0.75f).epsilon(1e-7));
  CHECK(rgb[3] == doctest::Approx(0.3f * 0.7f + 0.3f).epsilon(1e-6));
  CHECK(rgb[5] == doctest::Approx(0.5f * 0.7f + 0.3f).epsilon(1e-6));
  CHECK(contains(error_of([] { data::downsample2(data::RgbaImage{3, 2, std::vector<float>(24)}); }), "even sizes"));
}

TEST_CASE("multiscale: scale_camera divides focal, centre and size and multiplies lossmult by the area") {
  Camera cam;
  cam.width_px = 800;
  cam.height_px = 400;
  cam.focal_x_px = 1111.0;
  cam.focal_y_px = 1000.0;
  cam.center_x_px = 401.0;
  cam.center_y_px = 199.0;
  cam.camera_to_world = test::test_pose(1);
  const double lossmults[4] = {1, 4, 16, 64};
  for (int j = 0; j < 4; ++j) {
    const auto s = data::scale_camera(cam, 1u << j);
    CHECK(s.width_px == 800u >> j);
    CHECK(s.height_px == 400u >> j);
    CHECK(s.focal_x_px == 1111.0 / (1 << j));
    CHECK(s.center_y_px == 199.0 / (1 << j));
    CHECK(s.lossmult == lossmults[j]);
    // The centre of pixel (i, k) at scale j looks exactly where the centre of its 2^j × 2^j block at full
    // resolution does.
    for (int i : {0, 5}) {
      for (int k : {0, 3}) {
        const auto small = camera_ray(s, i + 0.5, k + 0.5);
        const double f = 1 << j;
        const auto full = camera_ray(cam, f * i + 0.5 * f, f * k + 0.5 * f);
        for (int a = 0; a < 3; ++a) CHECK(small.direction_world[a] == doctest::Approx(full.direction_world[a]).epsilon(1e-12));
      }
    }
    // The distance between neighbouring pixels' directions (the cone radius / (2/√12)) grows with the pixel.
    const auto p0 = camera_ray(s, 10.5, 7.5), p1 = camera_ray(s, 11.5, 7.5);
    double distance = 0;
    for (int a = 0; a < 3; ++a) distance += std::pow(p1.direction_world[a] - p0.direction_world[a], 2);
    CHECK(std::sqrt(distance) == doctest::Approx((1 << j) / 1111.0).epsilon(1e-12));
  }
}

TEST_CASE("multiscale: built on the fly while loading, with hand-checkable pixels at every scale") {
  test::TempDir dir;
  const uint32_t w = 16, h = 8;
  test::write_blender_split(dir.path(), "train", 2, w, h);
  data::LoadOptions options;
  options.scales = 4;
  const auto dataset = data::load_dataset(dir.path(), options);
  const auto& split = dataset.split("train");
  REQUIRE(split.num_images() == 8);
  CHECK(split.num_scales() == 4);
  const auto full_focal = split.cameras[0].focal_x_px;
  for (size_t c = 0; c < 8; ++c) {
    const uint32_t j = static_cast<uint32_t>(c % 4);  // image k's scales are consecutive, as the official order
    CHECK(split.scale_levels[c] == j);
    CHECK(split.cameras[c].width_px == w >> j);
    CHECK(split.cameras[c].lossmult == std::pow(4.0, j));
    CHECK(split.cameras[c].focal_x_px == full_focal / (1 << j));
    CHECK(split.files[c] == split.files[c - j]);
  }
  CHECK(split.num_pixels() == 2 * (128 + 32 + 8 + 2));
  // Scale 3 of image 1 has 2×1 pixels, each the mean of an 8×8 block of codes, composited on white.
  for (uint32_t x = 0; x < 2; ++x) {
    double mean[4] = {0, 0, 0, 0};
    for (uint32_t yy = 0; yy < 8; ++yy)
      for (uint32_t xx = 8 * x; xx < 8 * x + 8; ++xx)
        for (int c = 0; c < 4; ++c) mean[c] += test::test_code(1, xx, yy, c) / 255.0 / 64.0;
    for (int c = 0; c < 3; ++c) {
      CHECK(split.image_rgb(7)[3 * x + c] == doctest::Approx(mean[c] * mean[3] + 1.0 - mean[3]).epsilon(1e-5));
    }
  }
  options.scales = 5;  // 8 is not divisible by 16
  CHECK(contains(error_of([&] { data::load_dataset(dir.path(), options); }),
                 "r_0.png: 16x8 is not divisible by 16 for 5 scales; crop the images or use fewer scales"));
}

TEST_CASE("multiscale: make-multiscale writes the official layout and loads like the on-the-fly pyramid") {
  test::TempDir dir;
  const uint32_t w = 8, h = 8;
  test::write_blender_split(dir / "in", "train", 3, w, h);
  test::write_blender_split(dir / "in", "test", 1, w, h);
  data::write_multiscale(dir / "in", dir / "out", 4);
  const auto meta = io::read_json(dir / "out/metadata.json");
  CHECK(meta.contains("train"));
  CHECK(meta.contains("test"));
  CHECK_FALSE(meta.contains("val"));
  const auto& train = meta["train"];
  for (const char* key : {"file_path", "cam2world", "width", "height", "focal", "label", "near", "far", "lossmult",
                          "pix2cam"}) {
    REQUIRE(train.contains(key));
    CHECK(train[key].size() == 12);
  }
  CHECK(train["file_path"][5] == "images_train/001_d1.png");
  CHECK(train["lossmult"][7] == 64.0);
  CHECK(train["label"][6] == 2);
  CHECK(train["width"][6] == 2);
  CHECK(train["cam2world"][5].size() == 4);  // 4×4 as the official file

  data::LoadOptions on_the_fly;
  on_the_fly.scales = 4;
  const auto expected = data::load_dataset(dir / "in", on_the_fly);
  const auto loaded = data::load_dataset(dir / "out");
  CHECK(loaded.format == data::DatasetFormat::multiscale_blender);
  for (const char* name : {"train", "test"}) {
    const auto& a = expected.split(name);
    const auto& b = loaded.split(name);
    REQUIRE(a.num_images() == b.num_images());
    REQUIRE(a.pixel_offsets == b.pixel_offsets);
    CHECK(a.scale_levels == b.scale_levels);
    for (size_t c = 0; c < a.num_images(); ++c) {
      CHECK(b.cameras[c].focal_x_px == doctest::Approx(a.cameras[c].focal_x_px).epsilon(1e-12));
      CHECK(b.cameras[c].focal_y_px == doctest::Approx(a.cameras[c].focal_y_px).epsilon(1e-12));
      CHECK(b.cameras[c].center_x_px == doctest::Approx(a.cameras[c].center_x_px).epsilon(1e-12));
      CHECK(b.cameras[c].lossmult == a.cameras[c].lossmult);
      CHECK(b.cameras[c].width_px == a.cameras[c].width_px);
    }
    // Full resolution is stored exactly; smaller scales are rounded to 8 bits on disk: each of rgb and alpha
    // moves by at most 0.5/255, so the composite rgb·α + 1 − α moves by at most 1/255.
    for (size_t c = 0; c < a.num_images(); ++c) {
      const double tolerance = a.scale_levels[c] == 0 ? 0.0 : 1.0 / 255.0 + 1e-6;
      for (uint64_t p = 3 * a.pixel_offsets[c]; p < 3 * a.pixel_offsets[c + 1]; ++p) {
        REQUIRE(std::abs(a.rgb[p] - b.rgb[p]) <= tolerance);
      }
    }
  }
  CHECK(contains(error_of([&] { data::write_multiscale(dir / "out", dir / "again", 4); }), "already a multiscale"));
  CHECK(contains(error_of([&] { data::write_multiscale(dir / "in", dir / "in", 4); }), "must differ"));
  CHECK(contains(error_of([&] { data::load_dataset(dir / "out", on_the_fly); }), "is already multiscale"));
}
