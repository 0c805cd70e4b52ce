// Rendering from a checkpoint on the device (host/eval): splits in any chunking, supersampling, other
// resolutions, and the PNG/EXR outputs — with a tiny model trained a few steps in the test.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/error.hpp"
#include "data/paths/camera_path.hpp"
#include "data/dataset.hpp"
#include "eval/image_output.hpp"
#include "eval/image_renderer.hpp"
#include "io/color.hpp"
#include "io/exr.hpp"
#include "io/png.hpp"
#include "render_fixtures.hpp"

using namespace mipnerf;
namespace fs = std::filesystem;
using test::trained_model;

namespace {

const data::Split& test_split() {
  static const data::Dataset dataset = data::load_dataset(test::render_scene(), {});
  return dataset.split("test");
}

eval::RenderedImage render(const std::vector<Camera>& cameras, size_t index, eval::RenderSettings settings) {
  auto renderer = test::trained_renderer(cameras, settings);
  return renderer.render(index);
}

double max_abs_difference(const std::vector<float>& a, const std::vector<float>& b) {
  REQUIRE(a.size() == b.size());
  double d = 0.0;
  for (size_t i = 0; i < a.size(); ++i) d = std::max(d, std::abs(static_cast<double>(a[i]) - b[i]));
  return d;
}

double mean_abs_difference(const std::vector<float>& a, const std::vector<float>& b) {
  REQUIRE(a.size() == b.size());
  double d = 0.0;
  for (size_t i = 0; i < a.size(); ++i) d += std::abs(static_cast<double>(a[i]) - b[i]);
  return d / static_cast<double>(a.size());
}

double standard_deviation(const std::vector<float>& v) {
  double mean = 0.0, square = 0.0;
  for (float x : v) mean += x / static_cast<double>(v.size());
  for (float x : v) square += (x - mean) * (x - mean) / static_cast<double>(v.size());
  return std::sqrt(square);
}

// 2×2 box average of an [h][w][3] image (h, w even).
std::vector<float> downsample2(const std::vector<float>& rgb, uint32_t width, uint32_t height) {
  std::vector<float> out(3 * (width / 2) * (height / 2));
  for (uint32_t y = 0; y < height / 2; ++y) {
    for (uint32_t x = 0; x < width / 2; ++x) {
      for (int c = 0; c < 3; ++c) {
        float sum = 0.0f;
        for (uint32_t dy = 0; dy < 2; ++dy) {
          for (uint32_t dx = 0; dx < 2; ++dx) sum += rgb[3 * ((2 * y + dy) * width + 2 * x + dx) + c];
        }
        out[3 * (y * (width / 2) + x) + c] = sum / 4.0f;
      }
    }
  }
  return out;
}

void check_plausible(const eval::RenderedImage& image, const Camera& camera) {
  REQUIRE(image.rgb.size() == 3u * image.width * image.height);
  for (float v : image.rgb) REQUIRE(std::isfinite(v));
  for (float a : image.acc) {
    REQUIRE(a >= 0.0f);
    REQUIRE(a <= 1.0f + 1e-5f);  // Σ weights = 1 − transmittance, up to float rounding
  }
  // Expected depth along the optical axis lies inside the sampled range [near, far] (float rounding aside).
  for (float d : image.depth) {
    REQUIRE(d >= camera.near - 1e-4);
    REQUIRE(d <= camera.far + 1e-4);
  }
}

}  // namespace

TEST_CASE("render: a checkpoint records its data, and renders a split the same in any chunking") {
  CHECK(trained_model().step == 10);
  CHECK(trained_model().data_path == fs::absolute(test::render_scene()).lexically_normal().string());
  const auto& split = test_split();
  auto whole = test::trained_renderer(split.cameras, eval::RenderSettings{1024, 1, 0});
  // 100 rays is not a divisor of 256: a partial last chunk.
  auto chunked = test::trained_renderer(split.cameras, eval::RenderSettings{100, 1, 0});
  for (size_t i = 0; i < split.num_images(); ++i) {
    const auto a = whole.render(i), b = chunked.render(i);
    check_plausible(a, split.cameras[i]);
    CHECK(a.width == 16);
    // The render varies across the image (so the comparisons below compare something).
    MESSAGE("standard deviation of the colours " << standard_deviation(a.rgb));
    CHECK(standard_deviation(a.rgb) > 0.01);
    // Rays and samples are identical; only CLBlast's choice of GEMM kernel for another row count may reorder
    // float32 sums over a layer's ≤ 64 + 60 inputs: differences of a few ulp, far below 1e-5.
    CHECK(max_abs_difference(a.rgb, b.rgb) < 1e-5);
    CHECK(max_abs_difference(a.acc, b.acc) < 1e-5);
    CHECK(max_abs_difference(a.depth, b.depth) < 1e-4);  // depths are ~4: the same relative size
  }
}

TEST_CASE("render: supersampling averages jittered rays, reproducibly and whatever the chunking") {
  const auto& cameras = test_split().cameras;
  const auto centre = render(cameras, 0, {1024, 1, 0});
  const auto again = render(cameras, 0, {512, 1, 7});  // the seed does nothing without supersampling
  CHECK(max_abs_difference(centre.rgb, again.rgb) < 1e-5);
  const auto jittered = render(cameras, 0, {1024, 4, 11});
  check_plausible(jittered, cameras[0]);
  const auto same_seed = render(cameras, 0, {1024, 4, 11});
  CHECK(max_abs_difference(jittered.rgb, same_seed.rgb) == 0.0);  // the same rays, the same order of additions
  // Ray numbers are pixel indices, not positions in a chunk: another chunking jitters every pixel the same way
  // (a chunk-local numbering would move the jitter of most pixels and change them by far more than 1e-5).
  const auto other_chunks = render(cameras, 0, {100, 4, 11});  // 100 does not divide 256
  CHECK(max_abs_difference(jittered.rgb, other_chunks.rgb) < 1e-5);
  const auto other_seed = render(cameras, 0, {1024, 4, 12});
  // Different jitter, and both differ from the rays through the pixel centres ...
  CHECK(max_abs_difference(jittered.rgb, other_seed.rgb) > 1e-4);
  CHECK(max_abs_difference(jittered.rgb, centre.rgb) > 1e-4);
  // ... but stay inside the pixels: averaging within each pixel changes the image far less than a shift of one
  // whole pixel does.
  Camera shifted = cameras[0];
  shifted.center_x_px += 1.0;
  const auto moved = render({shifted}, 0, {1024, 1, 0});
  const double jitter_change = mean_abs_difference(jittered.rgb, centre.rgb);
  const double shift_change = mean_abs_difference(moved.rgb, centre.rgb);
  MESSAGE("mean |4x jittered - centre| " << jitter_change << ", mean |one-pixel shift - centre| " << shift_change);
  CHECK(jitter_change < 0.5 * shift_change);
  // More passes converge: 16 passes lie closer to 64 than 4 passes do (independent seeds: the difference's
  // variance is σ²(1/16 + 1/64) against σ²(1/4 + 1/64), over 768 values). If the passes shared their jitter, all
  // three would be one pass and equally far apart. At 8×8 pixels (a quarter of the rays).
  const std::vector<Camera> small{data::resize_camera(cameras[0], {0.5, 0, 0})};
  const auto many = render(small, 0, {1024, 64, 3});
  const auto sixteen = render(small, 0, {1024, 16, 5});
  const auto four = render(small, 0, {1024, 4, 6});
  MESSAGE("mean |16 - 64 passes| " << mean_abs_difference(sixteen.rgb, many.rgb) << ", mean |4 - 64 passes| "
                                   << mean_abs_difference(four.rgb, many.rgb));
  CHECK(mean_abs_difference(sixteen.rgb, many.rgb) < mean_abs_difference(four.rgb, many.rgb));
  CHECK_THROWS_WITH_AS(render(cameras, 0, {1024, 0, 0}), doctest::Contains("at least one ray per pixel"), Error);
}

TEST_CASE("render: at half and double resolution the model renders the same view at the new pixel size") {
  const Camera camera = test_split().cameras[1];
  const auto full = render({camera}, 0, {1024, 1, 0});
  const Camera half_camera = data::resize_camera(camera, {0.5, 0, 0});
  const auto half = render({half_camera}, 0, {1024, 1, 0});
  check_plausible(half, half_camera);
  CHECK(half.width == 8);
  CHECK(half.height == 8);
  const auto double_size = render({data::resize_camera(camera, {2.0, 0, 0})}, 0, {1024, 1, 0});
  CHECK(double_size.width == 32);
  // The box-filtered full-resolution render is what the half-size pixels cover: close to the half-size render.
  // A half-size camera whose focal length was not scaled (a 2x zoom of the centre) is much further from it.
  Camera zoomed = half_camera;
  zoomed.focal_x_px = camera.focal_x_px;
  zoomed.focal_y_px = camera.focal_y_px;
  const auto wrong = render({zoomed}, 0, {1024, 1, 0});
  const auto box = downsample2(full.rgb, 16, 16);
  const double right_difference = mean_abs_difference(half.rgb, box);
  const double wrong_difference = mean_abs_difference(wrong.rgb, box);
  MESSAGE("mean |half - box(full)| " << right_difference << ", with an unscaled focal length " << wrong_difference);
  CHECK(right_difference < 0.5 * wrong_difference);
  // Likewise the double-size render, box-filtered, gives back the full-size one.
  CHECK(mean_abs_difference(downsample2(double_size.rgb, 32, 32), full.rgb) < 0.5 * wrong_difference);
}

TEST_CASE("render: PNG holds the rendered values, EXR linear RGB with depth and accumulation") {
  const auto& camera = test_split().cameras[0];
  const auto image = render({camera}, 0, {1024, 1, 0});
  const auto dir = test::render_temp("outputs");
  fs::remove_all(dir);
  const auto written = eval::write_rendered_image((dir / "view").string(), image, eval::parse_output_formats("both"),
                                                  {{"mipnerf:step", "10"}});
  REQUIRE(written.size() == 2);
  const io::PngImage png = io::read_png((dir / "view.png").string());
  CHECK(png.width == 16);
  CHECK(png.bit_depth == 8);
  for (size_t p = 0; p < 16u * 16u; ++p) {
    for (int c = 0; c < 3; ++c) {
      const double expected = std::round(std::clamp(image.rgb[3 * p + c], 0.0f, 1.0f) * 255.0) / 255.0;
      REQUIRE(png.rgba[4 * p + c] == doctest::Approx(expected).epsilon(1e-6));  // 8-bit code, exactly
    }
  }
  const io::ExrImage exr = io::read_exr((dir / "view.exr").string());
  CHECK(exr.width == 16);
  REQUIRE(exr.rgb.size() == image.rgb.size());
  for (size_t k = 0; k < image.rgb.size(); ++k) {
    // Linear: the sRGB decoding of what the network produced (and not the encoded value itself, which is larger
    // than its decoding everywhere strictly between 0 and 1).
    REQUIRE(exr.rgb[k] == io::srgb_to_linear(image.rgb[k]));
    if (image.rgb[k] > 0.05f && image.rgb[k] < 0.95f) REQUIRE(exr.rgb[k] < image.rgb[k]);
  }
  CHECK(exr.depth == image.depth);  // scene units, float32, exactly
  CHECK(exr.acc == image.acc);
  CHECK(exr.attributes.at("mipnerf:step") == "10");
  // Converting back gives the rendered (encoded) colours to float32 rounding.
  std::vector<float> encoded(exr.rgb.size());
  io::linear_to_srgb(exr.rgb.data(), encoded.data(), encoded.size());
  CHECK(max_abs_difference(encoded, image.rgb) < 1e-6);
  CHECK_THROWS_WITH_AS(eval::parse_output_formats("gif"), doctest::Contains("expected png, exr or both"), Error);
  fs::remove_all(dir);
}
