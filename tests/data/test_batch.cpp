// The device side of a dataset: the packed camera layout agrees between host and kernels, a split is uploaded
// once, and the batch sampler (kernels/batch.cl) equals its CPU mirror (same Philox numbers) and is uniform.
#include <doctest/doctest.h>

#include <cmath>
#include <map>

#include "cl/kernel_sources.hpp"
#include "cl/launch.hpp"
#include "data/dataset.hpp"
#include "data/device_dataset.hpp"
#include "data/synthetic/procedural.hpp"
#include "support/data_fixtures.hpp"
#include "ops/batch.hpp"
#include "ops/rays.hpp"
#include "ref/batch.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

// A small multiscale split written on the fly: 3 training views of 16×16 at 4 scales (12 images of 4 sizes).
const data::Split& fixture_split() {
  static const data::Dataset dataset = [] {
    test::TempDir dir;
    data::SceneOptions options;
    options.size_px = 16;
    options.train_views = 3;
    options.val_views = options.test_views = 0;
    options.scales = 1;
    options.samples_per_axis = 2;
    data::write_procedural_scene(dir.path(), options);
    data::LoadOptions load;
    load.scales = 4;
    return data::load_dataset(dir.path(), load);
  }();
  return dataset.split("train");
}

struct HostBatch {
  std::vector<uint32_t> camera_ids, pixel_ids;
  std::vector<float> target_rgb, lossmult;
};

HostBatch run_device(ocl::Context& ctx, const data::DeviceDataset& device, const ops::BatchOptions& options,
                     uint32_t step, size_t rays) {
  ops::BatchArrays batch(ctx, rays);
  ops::batch_sample(ctx, device, options, step, batch);
  return {batch.camera_ids.download(ctx), batch.pixel_ids.download(ctx), batch.target_rgb.download(ctx),
          batch.lossmult.download(ctx)};
}

HostBatch run_mirror(const data::Split& split, const ops::BatchOptions& options, uint32_t step, size_t rays) {
  const std::vector<uint32_t> offsets(split.pixel_offsets.begin(), split.pixel_offsets.end());
  const auto cameras = pack_cameras(split.cameras);
  HostBatch out{std::vector<uint32_t>(rays), std::vector<uint32_t>(rays), std::vector<float>(3 * rays),
                std::vector<float>(rays)};
  ref::batch_sample(options.seed, step, offsets.data(), static_cast<uint32_t>(split.num_images()), split.rgb.data(),
                    cameras.data(), out.camera_ids.data(), out.pixel_ids.data(), out.target_rgb.data(),
                    out.lossmult.data(), static_cast<uint32_t>(rays), options.batching == ops::Batching::single_image);
  return out;
}

}  // namespace

TEST_CASE("device dataset: the kernels' CAMERA_* offsets equal camera_layout") {
  auto& ctx = test::test_context();
  const std::string probe =
      "__kernel void camera_layout_probe(__global int* out) {\n"
      "  out[0] = CAMERA_TO_WORLD; out[1] = CAMERA_FOCAL_X; out[2] = CAMERA_FOCAL_Y; out[3] = CAMERA_CENTER_X;\n"
      "  out[4] = CAMERA_CENTER_Y; out[5] = CAMERA_WIDTH; out[6] = CAMERA_HEIGHT; out[7] = CAMERA_NEAR;\n"
      "  out[8] = CAMERA_FAR; out[9] = CAMERA_LOSSMULT; out[10] = CAMERA_STRIDE;\n"
      "}\n";
  auto& program = ctx.program_from_sources(
      {{"common.cl", std::string(ocl::kernel_source("common.cl"))}, {"camera_layout_probe.cl", probe}});
  auto& kernel = program.kernel("camera_layout_probe");
  ocl::DeviceArray<int> out(ctx, 11, "camera layout [11]");
  ocl::set_args(kernel, "camera_layout_probe", out);
  ocl::launch_1d(ctx, kernel, 1, "camera_layout_probe");
  namespace L = camera_layout;
  CHECK(out.download(ctx) == std::vector<int>{L::camera_to_world, L::focal_x, L::focal_y, L::center_x, L::center_y,
                                              L::width, L::height, L::near, L::far, L::lossmult, L::stride});
}

TEST_CASE("device dataset: a split's cameras, pixels and offsets are uploaded as packed on the host") {
  auto& ctx = test::test_context();
  const auto& split = fixture_split();
  REQUIRE(split.num_images() == 12);
  const data::DeviceDataset device(ctx, split);
  CHECK(device.num_cameras() == 12);
  CHECK(device.num_pixels() == 3 * (256 + 64 + 16 + 4));
  CHECK(device.cameras().packed().download(ctx) == pack_cameras(split.cameras));
  CHECK(device.pixels_rgb().download(ctx) == split.rgb);
  const auto offsets = device.pixel_offsets().download(ctx);
  REQUIRE(offsets.size() == 13);
  for (size_t c = 0; c < 13; ++c) CHECK(offsets[c] == split.pixel_offsets[c]);
}

TEST_CASE("batch sampler: the device equals the CPU mirror exactly, in both batching modes") {
  auto& ctx = test::test_context();
  const auto& split = fixture_split();
  const data::DeviceDataset device(ctx, split);
  for (auto batching : {ops::Batching::all_images, ops::Batching::single_image}) {
    for (uint32_t step : {0u, 1u, 977u}) {
      const ops::BatchOptions options{0xfeedface12345ULL, batching};
      const size_t rays = 1000;  // not a multiple of the work-group size
      const auto got = run_device(ctx, device, options, step, rays);
      const auto want = run_mirror(split, options, step, rays);
      CHECK(got.camera_ids == want.camera_ids);
      CHECK(got.pixel_ids == want.pixel_ids);
      CHECK(got.target_rgb == want.target_rgb);
      CHECK(got.lossmult == want.lossmult);
      // Every ray's target is its pixel's colour, and its lossmult its camera's.
      for (size_t i = 0; i < rays; ++i) {
        const uint32_t c = got.camera_ids[i], p = got.pixel_ids[i];
        REQUIRE(c < split.num_images());
        REQUIRE(p < split.cameras[c].width_px * split.cameras[c].height_px);
        for (int k = 0; k < 3; ++k) REQUIRE(got.target_rgb[3 * i + k] == split.image_rgb(c)[3 * p + k]);
        REQUIRE(got.lossmult[i] == static_cast<float>(split.cameras[c].lossmult));
      }
      if (batching == ops::Batching::single_image) {
        for (size_t i = 1; i < rays; ++i) REQUIRE(got.camera_ids[i] == got.camera_ids[0]);
      }
    }
  }
  // The step changes the batch; the same (seed, step) repeats it.
  const ops::BatchOptions options{5, ops::Batching::all_images};
  const auto a = run_device(ctx, device, options, 3, 64), b = run_device(ctx, device, options, 3, 64),
             c = run_device(ctx, device, options, 4, 64);
  CHECK(a.pixel_ids == b.pixel_ids);
  CHECK(a.pixel_ids != c.pixel_ids);
}

TEST_CASE("batch sampler: all_images draws every pixel of the split with equal probability") {
  auto& ctx = test::test_context();
  const auto& split = fixture_split();
  const data::DeviceDataset device(ctx, split);
  const uint64_t pixels = split.num_pixels();  // 1020
  const size_t rays = 200000;
  std::vector<double> count(pixels, 0.0);
  const auto batch = run_device(ctx, device, {42, ops::Batching::all_images}, 0, rays);
  for (size_t i = 0; i < rays; ++i) count[split.pixel_offsets[batch.camera_ids[i]] + batch.pixel_ids[i]] += 1.0;
  // Pearson's chi-square over 1020 cells (1019 degrees of freedom: mean 1019, sd 45): 1019 + 6·45 ≈ 1290 is
  // a 6-sigma bound; a sampler that favoured small images or skipped pixels would be far above it.
  const double expected = static_cast<double>(rays) / pixels;
  double chi2 = 0.0;
  for (double n : count) chi2 += (n - expected) * (n - expected) / expected;
  MESSAGE("chi-square over " << pixels << " pixels: " << chi2);
  CHECK(chi2 < 1290.0);
  // Per scale: images of 4^-j the pixels get 4^-j the rays.
  std::map<uint32_t, double> per_level;
  for (size_t i = 0; i < rays; ++i) per_level[split.scale_levels[batch.camera_ids[i]]] += 1.0;
  for (uint32_t j = 0; j < 4; ++j) {
    const double share = 3.0 * (256 >> (2 * j)) / pixels;
    const double sd = std::sqrt(rays * share * (1 - share));
    CHECK(std::abs(per_level[j] - rays * share) < 6 * sd);
  }
}

TEST_CASE("batch sampler: single_image picks images uniformly and pixels uniformly within them") {
  auto& ctx = test::test_context();
  const auto& split = fixture_split();
  const data::DeviceDataset device(ctx, split);
  const uint32_t steps = 2400;
  std::vector<double> images(12, 0.0);
  std::vector<double> pixels_of_smallest(4, 0.0);  // 2×2 images (scale 3)
  for (uint32_t step = 0; step < steps; ++step) {
    const auto batch = run_device(ctx, device, {9, ops::Batching::single_image}, step, 8);
    images[batch.camera_ids[0]] += 1.0;
    if (split.scale_levels[batch.camera_ids[0]] == 3) {
      for (uint32_t p : batch.pixel_ids) pixels_of_smallest[p] += 1.0;
    }
  }
  // 2400 steps over 12 images: 200 each, sd ≈ 13.5; 6 sigma ≈ 81.
  for (double n : images) CHECK(std::abs(n - 200.0) < 81.0);
  // About 600 steps land on a 2×2 image, 8 rays each: ~1200 per pixel, sd ≈ 30 (plus the step count's spread).
  const double total = pixels_of_smallest[0] + pixels_of_smallest[1] + pixels_of_smallest[2] + pixels_of_smallest[3];
  for (double n : pixels_of_smallest) CHECK(std::abs(n - total / 4) < 6 * std::sqrt(total * 0.25 * 0.75));
}

TEST_CASE("batch sampler + ray kernel: device rays of a dataset batch match camera_ray at every scale") {
  auto& ctx = test::test_context();
  const auto& split = fixture_split();
  const data::DeviceDataset device(ctx, split);
  const size_t rays = 700;
  ops::BatchArrays batch(ctx, rays);
  ops::batch_sample(ctx, device, {77, ops::Batching::all_images}, 5, batch);
  ops::RayBundle bundle(ctx, rays);
  ops::Rays stage(ctx, RaysOptions{});
  stage.fwd({device.cameras().packed(), batch.camera_ids, batch.pixel_ids, rays}, bundle);
  const auto camera_ids = batch.camera_ids.download(ctx), pixel_ids = batch.pixel_ids.download(ctx);
  const auto o = bundle.origins.download(ctx), d = bundle.directions.download(ctx), r = bundle.radii.download(ctx),
             n = bundle.near.download(ctx), f = bundle.far.download(ctx), l = bundle.lossmult.download(ctx),
             batch_lossmult = batch.lossmult.download(ctx);
  std::map<uint32_t, int> levels_seen;
  for (size_t i = 0; i < rays; ++i) {
    const auto& cam = split.cameras[camera_ids[i]];
    const uint32_t x = pixel_ids[i] % cam.width_px, y = pixel_ids[i] / cam.width_px;
    const auto expected = camera_ray(cam, x + 0.5, y + 0.5);
    // float32 on the device: origins are copied (|o| = 4, ulp 5e-7); directions are ~1 in size, computed from
    // float-rounded cameras in a few operations: 1e-5 absolute is ~40 ulps.
    for (int k = 0; k < 3; ++k) {
      REQUIRE(std::abs(o[3 * i + k] - expected.origin_world[k]) < 1e-5);
      REQUIRE(std::abs(d[3 * i + k] - expected.direction_world[k]) < 1e-5);
    }
    // The cone radius follows the image's pixel size: the distance to the next pixel's direction, times 2/√12.
    const auto next = camera_ray(cam, x + 1.5, y + 0.5);
    double step = 0;
    for (int k = 0; k < 3; ++k) step += std::pow(next.direction_world[k] - expected.direction_world[k], 2);
    REQUIRE(r[i] == doctest::Approx(std::sqrt(step) * 2.0 / std::sqrt(12.0)).epsilon(1e-5));
    REQUIRE(n[i] == 2.0f);
    REQUIRE(f[i] == 6.0f);
    REQUIRE(l[i] == static_cast<float>(cam.lossmult));
    REQUIRE(batch_lossmult[i] == l[i]);
    ++levels_seen[split.scale_levels[camera_ids[i]]];
  }
  CHECK(levels_seen.size() == 4);  // every scale was exercised
}
