// Every compile-time specialisation of the ray-math kernels is built and run against the reference: ray shape
// (cone/cylinder), background (none/black/white), view dependence (on/off) with unit or raw view directions, sub-pixel
// jitter, disparity sampling, the density activations and the density noise. The registry is the stage list
// (host/ops/stage_list.cpp), which the kernel benchmark walks too: a new stage or option value is added there, and
// each stage has its check here (check_stage, whose switch over StageId makes a missing check a compile error).
#include <doctest/doctest.h>

#include <set>
#include <string>

#include "core/camera.hpp"
#include "kernel_checks.hpp"
#include "ops/activations.hpp"
#include "ops/encode.hpp"
#include "ops/gaussian.hpp"
#include "ops/rays.hpp"
#include "ops/render.hpp"
#include "ops/resample.hpp"
#include "ops/sample.hpp"
#include "ops/stage_list.hpp"
#include "ref/activations.hpp"
#include "ref/encode.hpp"
#include "ref/gaussian.hpp"
#include "ref/rays.hpp"
#include "ref/render.hpp"
#include "ref/resample.hpp"
#include "ref/sample.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

// The precise float32 bounds are the business of each stage's own tests; here a specialisation that builds but
// computes the wrong thing must fail: 1e-4 of the array's largest magnitude (a wrong branch is off by O(1)).
void check_matches(const char* what, const std::vector<float>& device, const std::vector<double>& reference) {
  double scale = 1e-30;
  for (double v : reference) scale = std::max(scale, std::abs(v));
  MIPNERF_CHECK_CLOSE(what, device, reference, [scale](size_t) { return 1e-4 * scale; });
}

// A small forward-facing scene (valid for both ray shapes): 3 cameras, 256 rays.
struct SmallScene {
  std::vector<float> cameras;
  std::vector<uint32_t> camera_ids, pixel_ids;
  SmallScene() {
    std::vector<Camera> cams(3);
    for (size_t c = 0; c < cams.size(); ++c) {
      cams[c].width_px = 40 + 10 * c;
      cams[c].height_px = 30;
      cams[c].focal_x_px = cams[c].focal_y_px = 50;
      cams[c].center_x_px = cams[c].width_px / 2.0;
      cams[c].center_y_px = 15;
      cams[c].camera_to_world[3] = 0.1 * c;
      cams[c].camera_to_world[11] = -0.2 * c;
    }
    cameras = pack_cameras(cams);
    for (uint32_t i = 0; i < 256; ++i) {
      camera_ids.push_back(i % 3);
      pixel_ids.push_back((i * 37) % (30 * 40));
    }
  }
};

void run_rays(const RaysOptions& options) {
  auto& ctx = test::test_context();
  const SmallScene s;
  const size_t n = s.camera_ids.size();
  auto cameras = test::upload(ctx, s.cameras, "cameras");
  auto ids = test::upload(ctx, s.camera_ids, "camera_ids"), pixels = test::upload(ctx, s.pixel_ids, "pixel_ids");
  auto rays = test::filled_rays(ctx, n, 7.0f);
  const RngKey key{3, 4, 5};
  ops::Rays(ctx, options).fwd({cameras, ids, pixels, n}, rays, key);
  std::vector<double> ro, rd, rv, rr, rn, rf, rl;
  ref::rays_fwd(options, test::to_double(s.cameras), s.camera_ids, s.pixel_ids, ro, rd, rv, rr, rn, rf, rl, n, 3, key);
  check_matches("origins", rays.origins.download(ctx), ro);
  check_matches("directions", rays.directions.download(ctx), rd);
  check_matches("radii", rays.radii.download(ctx), rr);
  if (options.view_dependence) {
    check_matches("viewdirs", rays.viewdirs.download(ctx), rv);
  } else {
    for (float x : rays.viewdirs.download(ctx)) REQUIRE(x == 7.0f);
  }
}

// Rays of 64 samples over [2, 6] with a simple density profile, for the sampling/Gaussian/render stages.
struct SmallRays {
  size_t n_rays = 64, n = 32;
  std::vector<float> origins, directions, radii, near, far, t_edges, density, rgb, weights, d_comp, d_acc;
  // The rays on the device (origins, directions, radii, near, far; viewdirs and lossmult unset: no stage here reads
  // them).
  ops::RayBundle upload(ocl::Context& ctx) const {
    ops::RayBundle rays(ctx, n_rays);
    rays.origins.upload(ctx, origins);
    rays.directions.upload(ctx, directions);
    rays.radii.upload(ctx, radii);
    rays.near.upload(ctx, near);
    rays.far.upload(ctx, far);
    return rays;
  }
  SmallRays() {
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (size_t ray = 0; ray < n_rays; ++ray) {
      for (int a = 0; a < 3; ++a) {
        origins.push_back(unit(rng) - 0.5f);
        directions.push_back(a == 2 ? -1.0f : 0.5f * (unit(rng) - 0.5f));
        d_comp.push_back(unit(rng) - 0.5f);
      }
      radii.push_back(1e-3f);
      near.push_back(2.0f);
      far.push_back(6.0f);
      d_acc.push_back(unit(rng) - 0.5f);
      for (size_t k = 0; k <= n; ++k) t_edges.push_back(2.0f + 4.0f * k / n + 0.01f * unit(rng));
      for (size_t i = 0; i < n; ++i) {
        density.push_back(4.0f * unit(rng) - 1.0f);  // raw values: both signs, for relu and softplus
        weights.push_back(unit(rng) < 0.3f ? unit(rng) : 0.0f);
        for (int c = 0; c < 3; ++c) rgb.push_back(4.0f * unit(rng) - 2.0f);
      }
    }
  }
};

void run_sample(const SampleOptions& options) {
  auto& ctx = test::test_context();
  const SmallRays s;
  const auto rays = s.upload(ctx);
  ocl::DeviceArray<float> t(ctx, s.n_rays * (s.n + 1), "t_edges");
  const RngKey key{1, 2, 3};
  ops::Sample(ctx, options).stratified({rays, s.n_rays, s.n}, t, key);
  std::vector<double> expected;
  ref::sample_stratified_fwd(options, test::to_double(s.near), test::to_double(s.far), expected, s.n_rays, s.n, key);
  check_matches("t_edges", t.download(ctx), expected);
}

void run_resample(const ResampleOptions& options) {
  auto& ctx = test::test_context();
  const SmallRays s;
  auto t = test::upload(ctx, s.t_edges, "t_edges"), w = test::upload(ctx, s.weights, "weights");
  ocl::DeviceArray<float> out(ctx, s.n_rays * (s.n + 1), "t_new");
  const RngKey key{1, 2, 3};
  ops::Resample(ctx).fwd(options, {t, w, s.n_rays, s.n, s.n}, out, key);
  std::vector<double> expected;
  ref::resample_fwd(options, test::to_double(s.t_edges), test::to_double(s.weights), expected, s.n_rays, s.n, s.n, key);
  check_matches("t_new", out.download(ctx), expected);
}

void run_gaussian(const GaussianOptions& options) {
  auto& ctx = test::test_context();
  const SmallRays s;
  const auto rays = s.upload(ctx);
  auto t = test::upload(ctx, s.t_edges, "t_edges");
  const size_t rows = s.n_rays * s.n;
  ocl::DeviceArray<float> means(ctx, 3 * rows, "means"), covs(ctx, 3 * rows, "covs");
  ops::Gaussian(ctx, options).fwd({rays, t, s.n_rays, s.n}, {means, covs});
  std::vector<double> rm, rc;
  ref::gaussian_fwd(options, test::to_double(s.origins), test::to_double(s.directions), test::to_double(s.radii),
                    test::to_double(s.t_edges), rm, rc, s.n_rays, s.n);
  check_matches("means", means.download(ctx), rm);
  check_matches("covs", covs.download(ctx), rc);
}

// The fused Gaussian + IPE (encode.cl includes gaussian.cl, so it has the ray shapes too), at the paper's degrees
// 0..15. The uniform 1e-4 of check_matches does not hold there: the float32 mean's error (≤ 2u·|o| + 12u·|t·d|,
// ~4e-6 at t = 6) times 2^l moves the argument by up to ~0.15 rad at degree 15, so each feature gets the bound of
// test_encode's fused test instead: 32u of itself, plus 2^l·|Δmean| and the variance's 35u·4^l·σ²/2, both scaled by
// the attenuation exp(−4^l·σ²/2) (the sine's slope is ≤ 1); twice the attenuated terms. A wrong branch is still
// off by O(1) wherever the attenuation is not negligible.
void run_encode(const GaussianOptions& options) {
  auto& ctx = test::test_context();
  const SmallRays s;
  const auto rays = s.upload(ctx);
  auto t = test::upload(ctx, s.t_edges, "t_edges");
  const size_t rows = s.n_rays * s.n;
  const ops::GaussianInputs in{rays, t, s.n_rays, s.n};
  const EncodingOptions encoding;  // degrees 0..15
  const size_t width = encoding.ipe_width(), half = width / 2;
  ocl::DeviceArray<float> features(ctx, rows * width, "features");
  ops::Encode(ctx, options).gaussian_ipe(encoding, in, features);
  std::vector<double> rf, means, covs;
  ref::gaussian_ipe_fwd(options, encoding, test::to_double(s.origins), test::to_double(s.directions),
                        test::to_double(s.radii), test::to_double(s.t_edges), rf, s.n_rays, s.n);
  ref::gaussian_fwd(options, test::to_double(s.origins), test::to_double(s.directions), test::to_double(s.radii),
                    test::to_double(s.t_edges), means, covs, s.n_rays, s.n);
  const double u = test::kUnitRoundoff;
  MIPNERF_CHECK_CLOSE("gaussian_ipe features", features.download(ctx), rf, [&](size_t i) {
    const size_t row = i / width, k = i % width, l = (k % half) / 3, a = k % 3, ray = row / s.n;
    const double scale = std::ldexp(1.0, static_cast<int>(l)), var = covs[3 * row + a];
    const double o = s.origins[3 * ray + a];
    const double mean_err = 2 * u * std::abs(o) + 12 * u * std::abs(means[3 * row + a] - o);
    const double atten = std::exp(-0.5 * var * scale * scale);
    return 32 * u * std::abs(rf[i]) + 1e-37 + 2 * atten * (scale * mean_err + 35 * u * var * scale * scale / 2);
  });
}

// The activations stage on its own.
void run_activations(const ActivationOptions& activation) {
  auto& ctx = test::test_context();
  const SmallRays s;
  const size_t rows = s.n_rays * s.n;
  auto raw_rgb = test::upload(ctx, s.rgb, "raw_rgb"), raw_density = test::upload(ctx, s.density, "raw_density");
  ocl::DeviceArray<float> density(ctx, rows, "density"), rgb(ctx, 3 * rows, "rgb");
  ops::Activations(ctx, activation).fwd({raw_density, raw_rgb, rows}, {density, rgb});
  std::vector<double> ref_density, ref_rgb;
  ref::activations_fwd(activation, test::to_double(s.density), test::to_double(s.rgb), ref_density, ref_rgb, rows);
  check_matches("density", density.download(ctx), ref_density);
  check_matches("rgb", rgb.download(ctx), ref_rgb);
}

void run_render(const RenderOptions& options, const ActivationOptions& activation) {
  // The activations stage on its own, then the fused render on raw values (which exercises both sets of options).
  run_activations(activation);
  auto& ctx = test::test_context();
  const SmallRays s;
  const size_t rows = s.n_rays * s.n;
  auto raw_rgb = test::upload(ctx, s.rgb, "raw_rgb"), raw_density = test::upload(ctx, s.density, "raw_density");
  auto t = test::upload(ctx, s.t_edges, "t_edges");
  const auto rays = s.upload(ctx);
  auto d_comp = test::upload(ctx, s.d_comp, "d_comp_rgb"), d_acc = test::upload(ctx, s.d_acc, "d_acc");
  ocl::DeviceArray<float> comp(ctx, 3 * s.n_rays, "comp_rgb"), acc(ctx, s.n_rays, "acc");
  ocl::DeviceArray<float> distance(ctx, s.n_rays, "distance"), weights(ctx, rows, "weights");
  ocl::DeviceArray<float> d_raw_rgb(ctx, 3 * rows, "d_raw_rgb"), d_raw_density(ctx, rows, "d_raw_density");
  ops::Render render(ctx, options, activation);
  const ops::RenderInputs in{raw_rgb, raw_density, t, rays, s.n_rays, s.n};
  const DensityNoiseKey noise{{3, 4, 5}, 1};  // read only by the density-noise specialisation
  render.raw_fwd(in, {comp, acc, distance, weights}, noise);
  render.raw_bwd(in, weights, {d_comp, &d_acc}, {d_raw_rgb, d_raw_density}, noise);
  std::vector<double> rc, ra, rd, rw, rgr, rgd;
  const auto d_acc_ref = test::to_double(s.d_acc);
  ref::render_raw_fwd(options, activation, test::to_double(s.rgb), test::to_double(s.density),
                      test::to_double(s.t_edges), test::to_double(s.directions), rc, ra, rd, rw, s.n_rays, s.n, noise);
  ref::render_raw_bwd(options, activation, test::to_double(s.rgb), test::to_double(s.density),
                      test::to_double(s.t_edges), test::to_double(s.directions), rw, test::to_double(s.d_comp),
                      &d_acc_ref, rgr, rgd, s.n_rays, s.n, noise);
  check_matches("comp_rgb", comp.download(ctx), rc);
  check_matches("acc", acc.download(ctx), ra);
  check_matches("distance", distance.download(ctx), rd);
  check_matches("d_raw_rgb", d_raw_rgb.download(ctx), rgr);
  check_matches("d_raw_density", d_raw_density.download(ctx), rgd);
}

// Checks one specialisation of a stage of the list against the reference; a stage without its case does not compile
// (-Werror=switch).
void check_stage(ops::StageId id, const ops::RayMathOptions& o) {
  switch (id) {
    case ops::StageId::rays: return run_rays(o.rays);
    case ops::StageId::sample: return run_sample(o.sample);
    case ops::StageId::gaussian: return run_gaussian(o.gaussian);
    case ops::StageId::encode: return run_encode(o.gaussian);
    case ops::StageId::activations: return run_activations(o.activation);
    case ops::StageId::render: return run_render(o.render, o.activation);
    case ops::StageId::resample: return run_resample(o.resample);
  }
  FAIL("stage id " << static_cast<int>(id) << " has no check");
}

}  // namespace

TEST_CASE("specialisations: every ray shape, background, view dependence and activation builds and runs") {
  size_t count = 0;
  for (const auto& stage : ops::ray_math_stages()) {
    for (const auto& variant : stage.variants) {
      INFO("specialisation: " << stage.name << " " << variant.name);
      check_stage(stage.id, variant.options);
      ++count;
    }
  }
  // rays: shape × (view with unit or raw viewdirs, no view) × jitter; sample: lindisp × jitter; gaussian, encode:
  // shape; activations: mip-NeRF, NeRF; render: background × activations, and density noise; resample: mip-NeRF, NeRF.
  CHECK(count == 12 + 4 + 2 + 2 + 2 + 7 + 2);
}

TEST_CASE("specialisations: the stage list's stages have unique names and ids, each with a specialisation") {
  std::set<std::string> names;
  std::set<int> ids;
  for (const auto& stage : ops::ray_math_stages()) {
    INFO("stage " << stage.name);
    CHECK(names.insert(stage.name).second);
    CHECK(ids.insert(static_cast<int>(stage.id)).second);
    CHECK_FALSE(stage.variants.empty());
  }
}
