// Our ray-math kernels (host/ops) against the official mip.py functions' own outputs (tests/official/fixtures,
// written by make_vectors.py from google/mipnerf): Gaussians (cast_rays), IPE and PE, stratified sampling,
// resampling and volume rendering (the density noise: test_model.cpp, from the official model's own noisy output). The
// official values are float64 evaluations on float32 inputs, so each bound below is our float32 error alone, derived
// in the comment beside it. Random draws: the official functions were given our Philox draws (the fixture's xi); each
// test first checks that our RNG gives exactly those draws for the fixture's key.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/rng.hpp"
#include "core/stage_options.hpp"
#include "official_fixtures.hpp"
#include "ops/encode.hpp"
#include "ops/gaussian.hpp"
#include "ops/ray_bundle.hpp"
#include "ops/render.hpp"
#include "ops/resample.hpp"
#include "ops/sample.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;
using official::flat;
using official::kU;

namespace {

// A bundle whose origins, directions and radii (and near, far) are the given values; other arrays zero.
ops::RayBundle make_rays(ocl::Context& ctx, size_t n_rays, const std::vector<double>& origins,
                         const std::vector<double>& directions, const std::vector<double>& radii,
                         const std::vector<double>& near = {}, const std::vector<double>& far = {}) {
  ops::RayBundle rays(ctx, n_rays);
  const std::vector<float> zeros3(3 * n_rays, 0.0f), zeros(n_rays, 0.0f);
  rays.origins.upload(ctx, origins.empty() ? zeros3 : official::as_float(origins));
  rays.directions.upload(ctx, directions.empty() ? zeros3 : official::as_float(directions));
  rays.viewdirs.upload(ctx, zeros3);
  rays.radii.upload(ctx, radii.empty() ? zeros : official::as_float(radii));
  rays.near.upload(ctx, near.empty() ? zeros : official::as_float(near));
  rays.far.upload(ctx, far.empty() ? zeros : official::as_float(far));
  rays.lossmult.upload(ctx, std::vector<float>(n_rays, 1.0f));
  return rays;
}

RngKey key_of(const io::Json& key) {
  return {key.at("seed").get<uint64_t>(), key.at("step").get<uint32_t>(), key.at("first_ray").get<uint32_t>()};
}

// The official function was given xi [R][n] as its uniform draws; they must be exactly ours for the fixture's key.
void check_draws_are_ours(const io::Json& fx, size_t n_rays, size_t n_values) {
  const io::Json& key = fx.at("key");
  const RngKey k = key_of(key);
  const uint32_t stream = key.at("stream").get<uint32_t>();
  const auto xi = flat(fx.at("xi"), {n_rays, n_values});
  size_t mismatches = 0;
  for (size_t ray = 0; ray < n_rays; ++ray) {
    for (size_t j = 0; j < n_values; ++j) {
      const auto u =
          rng_uniform4(k.seed, k.first_ray + static_cast<uint32_t>(ray), k.step, static_cast<uint32_t>(j / 4), stream);
      if (static_cast<double>(u[j % 4]) != xi[ray * n_values + j]) ++mismatches;
    }
  }
  INFO("the fixture's draws are not our Philox draws for its key: regenerate with make_vectors.py");
  REQUIRE(mismatches == 0);
}

// t_var and r_var of a lifted Gaussian Σ = t_var·ddᵀ + r_var·(I − ddᵀ/|d|²) (official lift_gaussian), recovered
// from the official full covariance: dᵀΣd = t_var·|d|⁴ and tr Σ = t_var·|d|² + 2·r_var.
struct LiftedVariances {
  double t_var, r_var;
};
LiftedVariances lifted_variances(const double* full, const double* d) {
  double dsd = 0, dd = 0;
  for (int a = 0; a < 3; ++a) {
    dd += d[a] * d[a];
    for (int b = 0; b < 3; ++b) dsd += d[a] * full[3 * a + b] * d[b];
  }
  const double t_var = dsd / (dd * dd);
  return {t_var, 0.5 * (full[0] + full[4] + full[8] - t_var * dd)};
}

}  // namespace

TEST_CASE("cast_rays: our cone and cylinder Gaussians are the official means and diagonal covariances") {
  auto& ctx = test::test_context();
  const auto fx = official::fixture("cast_rays.json");
  const auto& in = fx.at("inputs");
  const size_t R = in.at("origins").size(), N = in.at("t_vals").at(0).size() - 1;
  const auto t = flat(in.at("t_vals"), {R, N + 1});
  const auto origins = flat(in.at("origins"), {R, 3}), dirs = flat(in.at("directions"), {R, 3});
  const auto radii = flat(in.at("radii"), {R});
  auto rays = make_rays(ctx, R, origins, dirs, radii);
  auto t_dev = official::upload(ctx, official::as_float(t), "t_edges [R][N+1]");

  for (const RayShape shape : {RayShape::cone, RayShape::cylinder}) {
    const std::string name = shape == RayShape::cone ? "cone" : "cylinder";
    CAPTURE(name);
    const auto& out = fx.at("outputs");
    const auto means = flat(out.at(name + "_diag").at("means"), {R, N, 3});
    const auto covs = flat(out.at(name + "_diag").at("covs"), {R, N, 3});
    const auto full = flat(out.at(name + "_full").at("covs"), {R, N, 3, 3});
    // Our kernels keep the diagonal only (the official diag=True path that mip-NeRF trains with); the official
    // full covariance's diagonal is the same numbers, so both official paths are covered by one comparison.
    // (Equal to float64 rounding, relative to the trace.)
    double worst = 0;
    for (size_t i = 0; i < R * N * 3; ++i) {
      const double* m = &full[9 * (i / 3)];
      worst = std::max(worst, std::abs(m[4 * (i % 3)] - covs[i]) / (m[0] + m[4] + m[8]));
    }
    CHECK(worst <= 1e-14);

    ocl::DeviceArray<float> means_dev(ctx, R * N * 3, "means [R][N][3]"), covs_dev(ctx, R * N * 3, "covs [R][N][3]");
    ops::Gaussian(ctx, {shape}).fwd({rays, t_dev, R, N}, {means_dev, covs_dev});
    const auto our_means = means_dev.download(ctx), our_covs = covs_dev.download(ctx);

    // mean = o + t_mean·d: t_mean is a few float operations on positive terms (≤ 8u relative), the product and sum
    // two more roundings: 16u of the magnitudes |o| and |t_mean·d| (= |mean − o|, from the official value).
    OFFICIAL_CHECK_AGREES(name + " means", our_means, means, [&](size_t i) {
      const double o = origins[3 * (i / (3 * N)) + i % 3];
      return 16 * kU * (std::abs(o) + std::abs(means[i] - o));
    });
    // cov_a = t_var·d_a² + r_var·(1 − d_a²/|d|²): t_var and r_var each within ~10u relative in the stable form
    // (mild cancellation for t0 = 0), the null-space factor within 4u absolute; 64u of t_var·d_a² + r_var covers both
    // with margin. Magnitudes from the official full covariance.
    OFFICIAL_CHECK_AGREES(name + " covariances (diagonal)", our_covs, covs, [&](size_t i) {
      const size_t ray = i / (3 * N), axis = i % 3;
      const auto v = lifted_variances(&full[9 * (i / 3)], &dirs[3 * ray]);
      const double d = dirs[3 * ray + axis];
      return 64 * kU * (std::abs(v.t_var) * d * d + std::abs(v.r_var));
    });
  }
}

TEST_CASE("integrated_pos_enc: our IPE is the official encoding, degrees 0 to 15, in its feature order") {
  auto& ctx = test::test_context();
  const auto fx = official::fixture("encode.json");
  const auto& ipe = fx.at("ipe");
  const size_t rows = ipe.at("inputs").at("x").size();
  const EncodingOptions options{ipe.at("min_deg").get<int>(), ipe.at("max_deg").get<int>()};
  const size_t width = static_cast<size_t>(options.ipe_width());
  const auto x = flat(ipe.at("inputs").at("x"), {rows, 3}), cov = flat(ipe.at("inputs").at("cov_diag"), {rows, 3});
  const auto f64 = flat(ipe.at("official_float64"), {rows, width});
  const auto f32 = flat(ipe.at("official_float32"), {rows, width});

  auto x_dev = official::upload(ctx, official::as_float(x), "means [rows][3]");
  auto cov_dev = official::upload(ctx, official::as_float(cov), "covs [rows][3]");
  ocl::DeviceArray<float> features(ctx, rows * width, "ipe [rows][96]");
  ops::Encode(ctx, {}).ipe(options, {x_dev, cov_dev, rows}, features);
  const auto ours = features.download(ctx);

  const int L = options.degrees();
  // Feature f of a row: half f / 3L (sines, cosines), degree l = (f mod 3L) / 3, axis f mod 3 (official order).
  auto degree = [&](size_t i) { return (i % width) % (3 * L) / 3; };
  auto damping = [&](size_t i) {  // e_l = exp(−½·4^l·var), the official expected_sin's factor
    return std::exp(-0.5 * std::ldexp(cov[3 * (i / width) + i % 3], 2 * static_cast<int>(degree(i))));
  };
  // Against the float64 official: the argument 2^l·x is exact in float32 (a power-of-two scaling of a float32 input),
  // so our error is OpenCL's sin/cos (≤ 4 ulp) and exp (≤ 3 ulp) and one product: 16u of e_l. A tiny floor keeps a
  // fully damped feature (e_l below float's range) from demanding exact zero.
  OFFICIAL_CHECK_AGREES("IPE vs the official in float64", ours, f64,
                        [&](size_t i) { return 16 * kU * std::max(damping(i), 1e-30); });

  // Against the official as it runs (float32): its argument for the cosines, y + π/2, is rounded (u·|y|), and
  // safe_sin reduces |y| ≥ 100π modulo float32(100π), off from 100π by δ, shifting the phase by ⌊|y|/100π⌋·δ plus a
  // rounding of the remainder (u·100π); XLA's float32 sin of the reduced argument adds ~2u·|arg|. This bound grows
  // with the argument's magnitude 2^l·|x|, up to ~1e-3 at degree 15.
  const double t32 = static_cast<double>(static_cast<float>(100 * M_PI));
  const double delta = std::abs(static_cast<double>(static_cast<long double>(t32) - 100 * M_PIl));
  OFFICIAL_CHECK_AGREES("IPE vs the official in float32", ours, f32, [&](size_t i) {
    const bool cosine = (i % width) >= static_cast<size_t>(3 * L);
    const double y = std::abs(std::ldexp(x[3 * (i / width) + i % 3], static_cast<int>(degree(i))));
    const double arg = y + (cosine ? M_PI / 2 : 0.0);
    double phase = (cosine ? kU * arg : 0.0) + 2 * kU * std::min(arg, t32);
    if (arg >= t32) phase += std::floor(arg / t32) * delta + kU * t32;
    return damping(i) * (phase + 32 * kU) + 1e-30;
  });
}

TEST_CASE("integrated_pos_enc of cast_rays: our fused Gaussian and IPE kernel is the official composition") {
  auto& ctx = test::test_context();
  const auto rays_fx = official::fixture("cast_rays.json");
  const auto fx = official::fixture("encode.json");
  const auto& in = rays_fx.at("inputs");
  const size_t R = in.at("origins").size(), N = in.at("t_vals").at(0).size() - 1;
  const auto t = flat(in.at("t_vals"), {R, N + 1});
  const auto origins = flat(in.at("origins"), {R, 3}), dirs = flat(in.at("directions"), {R, 3});
  const auto radii = flat(in.at("radii"), {R});
  const auto& fused = fx.at("fused");
  const EncodingOptions options{fused.at("min_deg").get<int>(), fused.at("max_deg").get<int>()};
  const size_t width = static_cast<size_t>(options.ipe_width());
  const auto means = flat(fused.at("means"), {R, N, 3}), covs = flat(fused.at("covs"), {R, N, 3});
  const auto features = flat(fused.at("features"), {R, N, width});
  const auto full = flat(rays_fx.at("outputs").at("cone_full").at("covs"), {R, N, 3, 3});

  auto rays = make_rays(ctx, R, origins, dirs, radii);
  auto t_dev = official::upload(ctx, official::as_float(t), "t_edges [R][N+1]");
  ocl::DeviceArray<float> out(ctx, R * N * width, "features [R·N][96]");
  ops::Encode(ctx, {RayShape::cone}).gaussian_ipe(options, {rays, t_dev, R, N}, out);
  const auto ours = out.download(ctx);

  const int L = options.degrees();
  // The Gaussian's own float32 errors (the cast_rays bounds: 16u on the mean's terms, 64u on the covariance's) move
  // the feature e_l·sin(2^l·μ) by 2^l·Δμ in phase and e_l·expm1(½·4^l·Δvar) in damping; plus 16u·e_l as for IPE.
  OFFICIAL_CHECK_AGREES("fused Gaussian + IPE vs the official", ours, features, [&](size_t i) {
    const size_t row = i / width, axis = i % 3, ray = row / N;
    const int l = static_cast<int>((i % width) % (3 * L) / 3);
    const double o = origins[3 * ray + axis], mu = means[3 * row + axis], var = covs[3 * row + axis];
    const auto v = lifted_variances(&full[9 * row], &dirs[3 * ray]);
    const double d = dirs[3 * ray + axis];
    const double mean_error = 16 * kU * (std::abs(o) + std::abs(mu - o));
    const double var_error = 64 * kU * (std::abs(v.t_var) * d * d + std::abs(v.r_var));
    const double e = std::exp(-0.5 * std::ldexp(var, 2 * l));
    return e * (std::ldexp(mean_error, l) + 16 * kU) + e * std::expm1(0.5 * std::ldexp(var_error, 2 * l)) + 1e-30;
  });
}

TEST_CASE("pos_enc: our view-direction encoding is the official one, degrees 0 to 3 with the identity first") {
  auto& ctx = test::test_context();
  const auto fx = official::fixture("encode.json");
  const auto& pe = fx.at("pe");
  const size_t rows = pe.at("inputs").at("x").size();
  EncodingOptions options{pe.at("min_deg").get<int>(), pe.at("max_deg").get<int>()};
  options.append_identity = pe.at("append_identity").get<bool>();
  const size_t width = static_cast<size_t>(options.pe_width());
  const auto x = flat(pe.at("inputs").at("x"), {rows, 3});
  const auto features = flat(pe.at("features"), {rows, width});
  auto x_dev = official::upload(ctx, official::as_float(x), "viewdirs [R][3]");
  ocl::DeviceArray<float> out(ctx, rows * width, "pe [R][27]");
  ops::Encode(ctx, {}).pe(options, {x_dev, rows}, out);
  // The identity is copied exactly; sin/cos of 2^l·x (exact arguments, |x| ≤ 1, l ≤ 3) within OpenCL's 4 ulp: 8u.
  OFFICIAL_CHECK_AGREES("PE vs the official", out.download(ctx), features, official::constant_bound(8 * kU));
}

TEST_CASE("sample_along_rays: our stratified edges are the official ones, given the same draws") {
  auto& ctx = test::test_context();
  const auto fx = official::fixture("sample.json");
  const auto& in = fx.at("inputs");
  const size_t R = in.at("near").size(), N = in.at("num_samples").get<size_t>();
  check_draws_are_ours(fx, R, N + 1);
  const auto near = flat(in.at("near"), {R}), far = flat(in.at("far"), {R});
  auto rays = make_rays(ctx, R, {}, {}, {}, near, far);
  const RngKey key = key_of(fx.at("key"));
  for (const auto& c : fx.at("cases")) {
    SampleOptions options;
    options.randomized = c.at("randomized").get<bool>();
    options.lindisp = c.at("lindisp").get<bool>();
    CAPTURE(options.randomized);
    CAPTURE(options.lindisp);
    const auto expected = flat(c.at("t_vals"), {R, N + 1});
    ocl::DeviceArray<float> t_edges(ctx, R * (N + 1), "t_edges [R][N+1]");
    ops::Sample(ctx, options).stratified({rays, R, N}, t_edges, key);
    // An edge is ≤ 6 float operations on positive terms (the lerp or the disparity lerp, the midpoints, the jitter):
    // 16u of |t|.
    OFFICIAL_CHECK_AGREES("t_vals", t_edges.download(ctx), expected,
                          [&](size_t i) { return 16 * kU * std::abs(expected[i]); });
  }
}

namespace {

// The resampling fixture: inputs, our draws' key, and the per-ray bound of a new edge.
struct ResampleCase {
  io::Json fx;
  size_t R = 0, N = 0;
  std::vector<double> t, w, ray_bound;
  double padding = 0;
  RngKey key;
};

ResampleCase load_resample_case() {
  ResampleCase c;
  c.fx = official::fixture("resample.json");
  const auto& in = c.fx.at("inputs");
  c.R = in.at("weights").size();
  c.N = in.at("weights").at(0).size();
  const size_t R = c.R, N = c.N;
  check_draws_are_ours(c.fx, R, N + 1);
  c.t = flat(in.at("t_vals"), {R, N + 1});
  c.w = flat(in.at("weights"), {R, N});
  c.padding = in.at("resample_padding").get<double>();
  c.key = key_of(c.fx.at("key"));
  // Per ray: a new edge is t_k + frac·(t_{k+1} − t_k), frac = (u − cdf_k)/p_k. Our CDF is a float32 running sum of
  // N terms (≤ 2N·u absolute), our u within 3u; the bin probability p_k ≥ padding / (2·Σw + N·padding) (blur-pool at
  // most doubles the sum), so frac moves by ≤ (4N + 8)·u / p_min of the widest bin, plus 4u·|t| for the lerp (below).
  c.ray_bound.resize(R);
  for (size_t r = 0; r < R; ++r) {
    double sum = 0, widest = 0;
    for (size_t i = 0; i < N; ++i) {
      sum += c.w[r * N + i];
      widest = std::max(widest, c.t[r * (N + 1) + i + 1] - c.t[r * (N + 1) + i]);
    }
    const double p_min = c.padding / (2 * sum + static_cast<double>(N) * c.padding);
    c.ray_bound[r] = (4.0 * static_cast<double>(N) + 8) * kU / p_min * widest;
  }
  return c;
}

std::vector<float> run_resample(const ResampleCase& c, const ResampleOptions& options) {
  auto& ctx = test::test_context();
  auto t_dev = official::upload(ctx, official::as_float(c.t), "t_edges [R][N+1]");
  auto w_dev = official::upload(ctx, official::as_float(c.w), "weights [R][N]");
  ocl::DeviceArray<float> t_new(ctx, c.R * (c.N + 1), "t_new [R][N+1]");
  ops::Resample(ctx).fwd(options, {t_dev, w_dev, c.R, c.N, c.N}, t_new, c.key);
  return t_new.download(ctx);
}

}  // namespace

TEST_CASE("resample_along_rays: our resampled edges are the official ones, blur-pool and padding 0.01") {
  const auto c = load_resample_case();
  for (const auto& official_case : c.fx.at("cases")) {
    ResampleOptions options;
    options.padding = static_cast<float>(c.padding);
    options.blur = true;
    options.randomized = official_case.at("randomized").get<bool>();
    CAPTURE(options.randomized);
    const auto expected = flat(official_case.at("t_vals"), {c.R, c.N + 1});
    OFFICIAL_CHECK_AGREES("resampled t_vals", run_resample(c, options), expected,
                          [&](size_t i) { return c.ray_bound[i / (c.N + 1)] + 4 * kU * std::abs(expected[i]); });
  }
}

TEST_CASE("resample_along_rays: without the blur-pool (NeRF's resampling) does not match the official") {
  const auto c = load_resample_case();
  const auto& official_case = c.fx.at("cases").at(1);
  REQUIRE_FALSE(official_case.at("randomized").get<bool>());
  ResampleOptions options;
  options.padding = static_cast<float>(c.padding);
  options.blur = false;
  options.randomized = false;
  const auto expected = flat(official_case.at("t_vals"), {c.R, c.N + 1});
  // The spike and the smooth bump resample differently unblurred: edges move by a good part of a bin.
  OFFICIAL_CHECK_DISAGREES("resampled t_vals without blur-pool", run_resample(c, options), expected, 100.0,
                           [&](size_t i) { return c.ray_bound[i / (c.N + 1)] + 4 * kU * std::abs(expected[i]); });
}

TEST_CASE("volumetric_rendering: our composite, accumulation, distance and weights are the official ones") {
  auto& ctx = test::test_context();
  const auto fx = official::fixture("render.json");
  const auto& in = fx.at("inputs");
  const size_t R = in.at("density").size(), N = in.at("density").at(0).size();
  const auto rgb = flat(in.at("rgb"), {R, N, 3}), density = flat(in.at("density"), {R, N});
  const auto t = flat(in.at("t_vals"), {R, N + 1}), dirs = flat(in.at("dirs"), {R, 3});
  auto rays = make_rays(ctx, R, {}, dirs, {});
  auto rgb_dev = official::upload(ctx, official::as_float(rgb), "rgb [R][N][3]");
  auto density_dev = official::upload(ctx, official::as_float(density), "density [R][N]");
  auto t_dev = official::upload(ctx, official::as_float(t), "t_edges [R][N+1]");

  // The bound of weight i: s_j = σ_j·Δt_j·|d| within 4u each; α_i = −expm1(−s_i) within (4 + 2·s_i)·u relative;
  // T_i = exp(−Σ_{j<i} s_j) within (N + 6)·u·τ_i + 2u relative (a running float sum of optical depths τ). So
  // (N + 16)·u·(1 + τ_{i+1})·w_i. The optical depths are computed here from the inputs, for the bound only.
  std::vector<double> weight_bound(R * N), ray_weight_bound(R, 0.0);
  for (size_t r = 0; r < R; ++r) {
    const double norm =
        std::sqrt(dirs[3 * r] * dirs[3 * r] + dirs[3 * r + 1] * dirs[3 * r + 1] + dirs[3 * r + 2] * dirs[3 * r + 2]);
    double tau = 0;
    for (size_t i = 0; i < N; ++i) {
      tau += density[r * N + i] * (t[r * (N + 1) + i + 1] - t[r * (N + 1) + i]) * norm;
      weight_bound[r * N + i] = (static_cast<double>(N) + 16) * kU * (1 + tau);  // relative, × w_i below
    }
  }
  for (const bool white : {true, false}) {
    CAPTURE(white);
    const auto& out = fx.at("outputs").at(white ? "white" : "black");
    const auto comp = flat(out.at("comp_rgb"), {R, 3}), acc = flat(out.at("acc"), {R});
    const auto distance = flat(out.at("distance"), {R}), weights = flat(out.at("weights"), {R, N});
    ocl::DeviceArray<float> comp_dev(ctx, R * 3, "comp_rgb [R][3]"), acc_dev(ctx, R, "acc [R]"),
        distance_dev(ctx, R, "distance [R]"), weights_dev(ctx, R * N, "weights [R][N]");
    RenderOptions options;
    options.background = white ? Background::white : Background::black;
    ops::Render(ctx, options)
        .fwd({rgb_dev, density_dev, t_dev, rays, R, N}, {comp_dev, acc_dev, distance_dev, weights_dev});
    std::fill(ray_weight_bound.begin(), ray_weight_bound.end(), 0.0);
    for (size_t i = 0; i < R * N; ++i) ray_weight_bound[i / N] += weight_bound[i] * weights[i];

    OFFICIAL_CHECK_AGREES("weights", weights_dev.download(ctx), weights,
                          [&](size_t i) { return weight_bound[i] * weights[i] + 1e-30; });
    // acc = Σ w: the weights' bounds plus N·u of the running sum.
    OFFICIAL_CHECK_AGREES("acc", acc_dev.download(ctx), acc,
                          [&](size_t r) { return ray_weight_bound[r] + N * kU * acc[r] + 1e-30; });
    // comp = Σ w·c (+ 1 − acc): colours ≤ 1, so the weights' bounds (twice with a white background) plus 2N·u.
    OFFICIAL_CHECK_AGREES("comp_rgb", comp_dev.download(ctx), comp,
                          [&](size_t i) { return (white ? 2 : 1) * ray_weight_bound[i / 3] + 2 * N * kU; });
    // distance = Σ w·t_mid / acc (t_0 when acc = 0, official nan_to_num + clip): relative 2·Σ bound / acc + 2N·u.
    OFFICIAL_CHECK_AGREES("distance", distance_dev.download(ctx), distance, [&](size_t r) {
      const double rel = acc[r] > 0 ? 2 * ray_weight_bound[r] / acc[r] : 0.0;
      return (rel + 2 * N * kU) * std::abs(distance[r]);
    });
  }
}
