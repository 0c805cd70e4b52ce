// Encodings (kernels/encode.cl): IPE and PE against the reference, large arguments against long double, the
// feature order written out, σ² = 0 ≡ PE, σ² = 1e12 → 0, IPE against Monte Carlo, the fused Gaussian + IPE, and
// IPE = PE wherever a zero radius, an axis-aligned or a zero direction leaves no variance.
#include <doctest/doctest.h>

#include <array>
#include <cfloat>
#include <vector>

#include "kernel_checks.hpp"
#include "ops/encode.hpp"
#include "ops/gaussian.hpp"
#include "ref/encode.hpp"
#include "ref/gaussian.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;
using test::kUnitRoundoff;

namespace {

// ipe_fwd (pe_fwd) as Encode runs it with `items`: per (row, axis) with per_row_and_axis, else per (row, degree).
std::vector<float> run_ipe(const EncodingOptions& options, const std::vector<float>& means,
                           const std::vector<float>& covs,
                           ops::EncodeTuning::FusedItems items = ops::EncodeTuning::FusedItems::device_default) {
  auto& ctx = test::test_context();
  const size_t rows = means.size() / 3;
  auto means_dev = test::upload(ctx, means, "means"), covs_dev = test::upload(ctx, covs, "covs");
  auto features = test::filled(ctx, rows * options.ipe_width(), 7.0f, "ipe_features");
  ops::EncodeTuning tuning;
  tuning.fused_items = items;
  ops::Encode(ctx, {}, tuning).ipe(options, {means_dev, covs_dev, rows}, features);
  return features.download(ctx);
}

std::vector<float> run_pe(const EncodingOptions& options, const std::vector<float>& x,
                          ops::EncodeTuning::FusedItems items = ops::EncodeTuning::FusedItems::device_default) {
  auto& ctx = test::test_context();
  const size_t rows = x.size() / 3;
  auto x_dev = test::upload(ctx, x, "x");
  auto features = test::filled(ctx, rows * options.pe_width(), 7.0f, "pe_features");
  ops::EncodeTuning tuning;
  tuning.fused_items = items;
  ops::Encode(ctx, {}, tuning).pe(options, {x_dev, rows}, features);
  return features.download(ctx);
}

// Tolerance of one feature a·sin(y) (or cos): sin/cos within 4 ulp and exp within 3 ulp of their results (OpenCL
// C 1.2 §7.4), y and the exponent exact (power-of-two scalings of float inputs), one product: ≤ 16u relative;
// twice that. The absolute floor 1e-37 covers attenuations that underflow (or flush) to 0 near FLT_MIN.
double feature_tolerance(double reference) { return 32 * kUnitRoundoff * std::abs(reference) + 1e-37; }

// The fused kernel's work spread per row with a sincos every `sincos_every` degrees (1: a sincos per degree, the
// features of ipe_fwd bit for bit).
// The fused kernel's bound on feature i of [rows][96] (degrees 0..15): the feature's own 32u, plus 2^l times the
// float mean's error (≤ 2u·|o| + 12u·|t·d|, test_gaussian) in the argument and the variance's (≤ 35u relative)
// through the attenuation, twice those terms; with a sincos every K degrees the doubling's own bound adds
// atten·(2^j·8u + (2^j − 1)·3u), j doublings since the last sincos (encode.cl); K = 1 never doubles.
double fused_feature_tolerance(size_t i, const std::vector<double>& features, const std::vector<float>& origins,
                               const std::vector<double>& means_ref, const std::vector<double>& covs_ref,
                               size_t n_samples, int sincos_every) {
  const size_t row = i / 96, k = i % 96, l = (k % 48) / 3, a = k % 3, ray = row / n_samples;
  const double scale = std::ldexp(1.0, static_cast<int>(l));
  const double mean_err = 2 * kUnitRoundoff * std::abs(origins[3 * ray + a]) +
                          12 * kUnitRoundoff * std::abs(means_ref[3 * row + a] - origins[3 * ray + a]);
  const double var_err = 35 * kUnitRoundoff * covs_ref[3 * row + a] * scale * scale / 2;
  const double atten = std::exp(-0.5 * covs_ref[3 * row + a] * scale * scale);
  const int doublings = static_cast<int>(l) % sincos_every;
  const double doubling = doublings > 0 ? atten * ref::doubling_error_bound(doublings) : 0.0;
  return feature_tolerance(features[i]) + 2 * atten * (scale * mean_err + var_err) + doubling;
}

ops::EncodeTuning items_every(ops::EncodeTuning::FusedItems items, int sincos_every) {
  ops::EncodeTuning tuning;
  tuning.fused_items = items;
  tuning.sincos_every = sincos_every;
  return tuning;
}

ops::EncodeTuning per_row_every(int sincos_every) {
  return items_every(ops::EncodeTuning::FusedItems::per_row, sincos_every);
}

// Per row and, where the device has fp64 (its sin/cos reduce in double), per (row, axis); the latter's absence is
// checked to be refused. The fused kernels that can double angles, and the two ways ipe_fwd and pe_fwd run (per
// (row, degree) unless per (row, axis)).
std::vector<ops::EncodeTuning::FusedItems> row_and_axis_items(ocl::Context& ctx) {
  if (ctx.device_info().has_fp64) {
    return {ops::EncodeTuning::FusedItems::per_row, ops::EncodeTuning::FusedItems::per_row_and_axis};
  }
  CHECK_THROWS(ops::Encode(ctx, {RayShape::cone}, items_every(ops::EncodeTuning::FusedItems::per_row_and_axis, 4)));
  return {ops::EncodeTuning::FusedItems::per_row};
}

const char* items_name(ops::EncodeTuning::FusedItems items) {
  return items == ops::EncodeTuning::FusedItems::per_row_and_axis ? "per (row, axis)" : "per row";
}

// ipe_fwd and pe_fwd's items under `items`, for messages.
const char* encoding_items_name(ops::EncodeTuning::FusedItems items) {
  return items == ops::EncodeTuning::FusedItems::per_row_and_axis ? "per (row, axis)" : "per (row, degree)";
}

}  // namespace

TEST_CASE("encode: IPE matches the CPU reference on 10,000 rows over degrees 0-15") {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> position(-4.0, 4.0);
  const size_t rows = 10000;
  std::vector<float> means(3 * rows), covs(3 * rows);
  for (auto& m : means) m = static_cast<float>(position(rng));
  for (size_t i = 0; i < covs.size(); ++i) {
    covs[i] = i % 97 == 0 ? 0.0f : static_cast<float>(test::log_uniform(rng, 1e-12, 10.0));
  }
  const EncodingOptions options;  // 0..15, the paper's L = 16
  REQUIRE(options.ipe_width() == 96);
  std::vector<double> features;
  ref::ipe_fwd(options, test::to_double(means), test::to_double(covs), features, rows);
  for (auto items : row_and_axis_items(test::test_context())) {
    INFO("items " << encoding_items_name(items));
    const auto dev = run_ipe(options, means, covs, items);
    MIPNERF_CHECK_CLOSE("ipe_features", dev, features, [&](size_t i) { return feature_tolerance(features[i]); });
  }
}

TEST_CASE("encode: IPE of large arguments (up to 2^15 x 100) is accurate against long double") {
  // σ² = 0 so every feature is a bare sin/cos of y = 2^l·μ: the hardest case for range reduction. |μ| up to 100
  // gives |y| up to 3.3e6 (a Blender scene's |μ| ≤ 4 reaches 1.3e5).
  std::mt19937 rng(22);
  std::uniform_real_distribution<double> magnitude(-2.0, 2.0);
  const size_t rows = 4000;
  std::vector<float> means(3 * rows), covs(3 * rows, 0.0f);
  for (size_t i = 0; i < means.size(); ++i) {
    const double sign = i % 2 ? 1.0 : -1.0;
    means[i] = static_cast<float>(sign * std::pow(10.0, magnitude(rng)));
  }
  const EncodingOptions options;
  for (auto items : row_and_axis_items(test::test_context())) {
    INFO("items " << encoding_items_name(items));
    const auto dev = run_ipe(options, means, covs, items);
    const int n_degrees = options.degrees();
    double worst_ulps = 0;
    size_t failures = 0;
    for (size_t row = 0; row < rows; ++row) {
      for (int l = 0; l < n_degrees; ++l) {
        for (int a = 0; a < 3; ++a) {
          long double s, c;
          ref::ipe_pair<long double>(means[3 * row + a], 0.0L, l, s, c);
          const float got[2] = {dev[row * 96 + 3 * l + a], dev[row * 96 + 48 + 3 * l + a]};
          const long double want[2] = {s, c};
          for (int k = 0; k < 2; ++k) {
            REQUIRE(std::isfinite(got[k]));
            const double ulp = std::nextafter(std::abs(float(want[k])), INFINITY) - std::abs(float(want[k]));
            const double ulps = static_cast<double>(std::abs(got[k] - want[k])) / ulp;
            worst_ulps = std::max(worst_ulps, ulps);
            if (ulps > 4.0) ++failures;  // the OpenCL bound for sin and cos
          }
        }
      }
    }
    if (std::getenv("MIPNERF_TEST_VERBOSE")) MESSAGE("worst error " << worst_ulps << " ulp");
    INFO("worst error " << worst_ulps << " ulp of the long-double sin/cos of the exact float argument");
    CHECK(failures == 0);
  }
}

TEST_CASE("encode: feature order is sines then cosines, index l times 3 plus axis") {
  const std::vector<float> mean = {0.3f, -1.1f, 2.5f}, var = {0.01f, 0.02f, 0.04f};
  EncodingOptions options;
  options.min_deg = 1;
  options.max_deg = 3;  // degrees 1 and 2: L = 2, 12 features
  const auto ipe = run_ipe(options, mean, var);
  REQUIRE(ipe.size() == 12);
  for (int l = 0; l < 2; ++l) {
    for (int a = 0; a < 3; ++a) {
      const double scale = std::ldexp(1.0, options.min_deg + l);
      const double atten = std::exp(-0.5 * var[a] * scale * scale);
      CHECK(ipe[3 * l + a] == doctest::Approx(atten * std::sin(scale * mean[a])).epsilon(1e-6));
      CHECK(ipe[6 + 3 * l + a] == doctest::Approx(atten * std::cos(scale * mean[a])).epsilon(1e-6));
    }
  }
  options.append_identity = true;
  const auto pe = run_pe(options, mean);
  REQUIRE(pe.size() == 15);
  for (int a = 0; a < 3; ++a) CHECK(pe[a] == mean[a]);
  CHECK(pe[3 + 3 * 1 + 2] == doctest::Approx(std::sin(4.0 * mean[2])).epsilon(1e-6));  // l = 1 (degree 2), z
  CHECK(pe[3 + 6 + 0] == doctest::Approx(std::cos(2.0 * mean[0])).epsilon(1e-6));      // l = 0 (degree 1), x
}

TEST_CASE("encode: PE of view directions (27 features) and NeRF positions (63 features) match the reference") {
  std::mt19937 rng(23);
  std::normal_distribution<double> normal(0.0, 1.0);
  const size_t rows = 10000;
  std::vector<float> dirs(3 * rows), positions(3 * rows);
  for (size_t r = 0; r < rows; ++r) {
    double d[3] = {normal(rng), normal(rng), normal(rng)};
    const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int a = 0; a < 3; ++a) {
      dirs[3 * r + a] = static_cast<float>(d[a] / len);
      positions[3 * r + a] = static_cast<float>(2 * normal(rng));
    }
  }
  for (const auto& [max_deg, x] : {std::pair{4, &dirs}, std::pair{10, &positions}}) {
    EncodingOptions options;
    options.max_deg = max_deg;
    options.append_identity = true;
    REQUIRE(options.pe_width() == (max_deg == 4 ? 27 : 63));
    std::vector<double> features;
    ref::pe_fwd(options, test::to_double(*x), features, rows);
    for (auto items : row_and_axis_items(test::test_context())) {
      INFO("degrees 0.." << options.max_deg - 1 << ", items " << encoding_items_name(items));
      const auto dev = run_pe(options, *x, items);
      MIPNERF_CHECK_CLOSE("pe_features", dev, features, [&](size_t i) { return feature_tolerance(features[i]); });
    }
  }
  // Identity only (no degrees) is a copy.
  EncodingOptions identity_only;
  identity_only.max_deg = 0;
  identity_only.append_identity = true;
  for (auto items : row_and_axis_items(test::test_context())) CHECK(run_pe(identity_only, dirs, items) == dirs);
}

TEST_CASE("encode: IPE with zero variance equals PE bit for bit, and a huge variance gives 0 not NaN") {
  std::mt19937 rng(24);
  std::uniform_real_distribution<float> position(-50.0f, 50.0f);
  const size_t rows = 2000;
  std::vector<float> means(3 * rows);
  for (auto& m : means) m = position(rng);
  const EncodingOptions options;
  for (auto items : row_and_axis_items(test::test_context())) {
    INFO("items " << encoding_items_name(items));
    const auto ipe = run_ipe(options, means, std::vector<float>(3 * rows, 0.0f), items);
    const auto pe = run_pe(options, means, items);  // no identity: the same 96 features
    CHECK(ipe == pe);
  }
  // σ² = 1e12 (4^l·σ² up to 1e21) and σ² = +∞: every attenuation is exactly 0.
  for (float var : {1e12f, INFINITY}) {
    const auto wide = run_ipe(options, means, std::vector<float>(3 * rows, var));
    for (float f : wide) REQUIRE(f == 0.0f);
  }
  // A wide but finite variance attenuates the high degrees to exactly 0 and keeps the low ones.
  const auto mid = run_ipe(options, means, std::vector<float>(3 * rows, 1.0f));
  CHECK(test::all_finite(mid));
  CHECK(mid[3 * 15] == 0.0f);  // degree 15: exp(−0.5·4^15) = 0
}

TEST_CASE("encode: IPE is the expectation of sin and cos under the Gaussian (Monte Carlo)") {
  // E[sin(2^l·z)] for z ~ N(μ, σ²) is exp(−4^l·σ²/2)·sin(2^l·μ) (mip-NeRF §3.1).
  std::mt19937_64 rng(25);
  const std::vector<float> mean = {0.7f, -0.2f, 1.3f}, var = {0.05f, 0.002f, 0.3f};
  EncodingOptions options;
  options.max_deg = 4;
  const auto dev = run_ipe(options, mean, var);
  const size_t samples = 400000;
  for (int a = 0; a < 3; ++a) {
    std::normal_distribution<double> z(mean[a], std::sqrt(double(var[a])));
    std::vector<double> sum_sin(4, 0.0), sum_cos(4, 0.0);
    for (size_t s = 0; s < samples; ++s) {
      const double x = z(rng);
      for (int l = 0; l < 4; ++l) {
        sum_sin[l] += std::sin(std::ldexp(x, l));
        sum_cos[l] += std::cos(std::ldexp(x, l));
      }
    }
    for (int l = 0; l < 4; ++l) {
      // Standard error of a mean of values in [−1, 1]: ≤ 1/sqrt(M) = 1.6e-3; 5 standard errors, fixed seed.
      const double tol = 5.0 / std::sqrt(double(samples));
      CHECK(std::abs(dev[3 * l + a] - sum_sin[l] / samples) <= tol);
      CHECK(std::abs(dev[12 + 3 * l + a] - sum_cos[l] / samples) <= tol);
    }
  }
}

TEST_CASE("encode: zero radius, axis-aligned and zero directions - IPE is PE of the means where the covariance is 0") {
  // A cone or cylinder of radius exactly 0 keeps the spread along the ray, t_var·d_a², so IPE equals PE of the mean
  // exactly on the axes where that vanishes: every axis of a zero-width interval (t0 = t1: t_var = 0 as well), the
  // axes perpendicular to a ray along a coordinate axis, and every axis of a zero direction (the reference's
  // definition: covariance 0). There exp(−½·4^l·0) = 1 exactly, so the features must equal PE bit for bit;
  // everywhere they must match the reference within the fused test's bound (below).
  auto& ctx = test::test_context();
  std::mt19937 rng(27);
  std::uniform_real_distribution<double> unit(0.0, 1.0), signed_unit(-1.0, 1.0);
  const std::vector<std::array<float, 3>> dirs = {{1, 0, 0}, {0, -1, 0},          {0, 0, -1},          {0, 0, 2},
                                                  {0, 0, 0}, {0.3f, -1.2f, 0.5f}, {-0.7f, 0.2f, -1.9f}};
  const size_t n_samples = 24;
  std::vector<float> origins, directions, radii, t_edges;
  for (int copy = 0; copy < 20; ++copy) {
    for (const auto& d : dirs) {
      for (float radius : {0.0f, 1e-3f}) {
        for (int a = 0; a < 3; ++a) origins.push_back(static_cast<float>(3 * signed_unit(rng)));
        directions.insert(directions.end(), d.begin(), d.end());
        radii.push_back(radius);
        float t = copy % 4 == 0 ? 0.0f : static_cast<float>(2 + unit(rng));
        t_edges.push_back(t);
        for (size_t k = 0; k < n_samples; ++k) {
          if (unit(rng) > 0.25) t += static_cast<float>(test::log_uniform(rng, 1e-4, 0.1));  // a quarter empty
          t_edges.push_back(t);
        }
      }
    }
  }
  const size_t n_rays = radii.size(), rows = n_rays * n_samples;
  ops::RayBundle rays(ctx, n_rays);
  rays.origins.upload(ctx, origins);
  rays.directions.upload(ctx, directions);
  rays.radii.upload(ctx, radii);
  auto t = test::upload(ctx, t_edges, "t_edges");
  const EncodingOptions options;  // degrees 0..15
  const ops::GaussianInputs in{rays, t, n_rays, n_samples};
  for (auto shape : {RayShape::cone, RayShape::cylinder}) {
    INFO("ray shape " << static_cast<int>(shape));
    ocl::DeviceArray<float> means(ctx, 3 * rows, "means"), covs(ctx, 3 * rows, "covs");
    ops::Gaussian(ctx, {shape}).fwd(in, {means, covs});
    ops::Encode encode(ctx, {shape}, per_row_every(1));  // bit for bit needs a sincos per degree (see below for K > 1)
    auto fused = test::filled(ctx, rows * 96, 7.0f, "fused"), separate = test::filled(ctx, rows * 96, 7.0f, "ipe");
    auto pe = test::filled(ctx, rows * 96, 7.0f, "pe of the means");
    encode.gaussian_ipe(options, in, fused);
    encode.ipe(options, {means, covs, rows}, separate);
    encode.pe(options, {means, rows}, pe);
    const auto fused_values = fused.download(ctx), pe_values = pe.download(ctx);
    const auto cov_values = covs.download(ctx), mean_values = means.download(ctx);
    CHECK(fused_values == separate.download(ctx));
    size_t exact_axes = 0;
    for (size_t row = 0; row < rows; ++row) {
      for (int a = 0; a < 3; ++a) {
        if (cov_values[3 * row + a] != 0.0f) continue;
        ++exact_axes;
        for (int l = 0; l < 16; ++l) {
          for (size_t k : {size_t(3 * l + a), size_t(48 + 3 * l + a)}) {
            REQUIRE(fused_values[row * 96 + k] == pe_values[row * 96 + k]);
          }
        }
      }
    }
    // Zero directions (3 axes of 960 rows), radius-0 rays along an axis (2 axes of 1,920 rows), and the empty
    // intervals of the other radius-0 rays: more than 6,700 axes.
    CHECK(exact_axes > 6700);
    std::vector<double> features, means_ref, covs_ref;
    ref::gaussian_ipe_fwd({shape}, options, test::to_double(origins), test::to_double(directions),
                          test::to_double(radii), test::to_double(t_edges), features, n_rays, n_samples);
    ref::gaussian_fwd({shape}, test::to_double(origins), test::to_double(directions), test::to_double(radii),
                      test::to_double(t_edges), means_ref, covs_ref, n_rays, n_samples);
    for (float m : mean_values) REQUIRE(std::isfinite(m));
    // The fused test's bound: the feature's own 32u, plus 2^l times the float mean's error (≤ 2u·|o| + 12u·|t·d|,
    // test_gaussian) in the argument and the variance's (≤ 35u relative) through the attenuation; twice those terms.
    MIPNERF_CHECK_CLOSE("zero-radius and axis-aligned features", fused_values, features, [&](size_t i) {
      return fused_feature_tolerance(i, features, origins, means_ref, covs_ref, n_samples, 1);
    });
  }
}

TEST_CASE("encode: the fused Gaussian and IPE kernel equals gaussian_fwd then ipe_fwd") {
  auto& ctx = test::test_context();
  std::mt19937 rng(26);
  std::uniform_real_distribution<double> unit(0.0, 1.0), signed_unit(-1.0, 1.0);
  const size_t n_rays = test::batch_for_device(220, 32), n_samples = 48;  // 10,560 rows (1,536 under oclgrind)
  std::vector<float> origins, directions, radii, t_edges;
  for (size_t ray = 0; ray < n_rays; ++ray) {
    for (int a = 0; a < 3; ++a) {
      origins.push_back(static_cast<float>(3 * signed_unit(rng)));
      directions.push_back(static_cast<float>(signed_unit(rng)));
    }
    radii.push_back(static_cast<float>(test::log_uniform(rng, 1e-4, 1e-2)));
    float t = static_cast<float>(2 + unit(rng));
    for (size_t k = 0; k <= n_samples; ++k) {
      t_edges.push_back(t);
      t += static_cast<float>(test::log_uniform(rng, 1e-4, 0.1));
    }
  }
  ops::RayBundle rays(ctx, n_rays);
  rays.origins.upload(ctx, origins);
  rays.directions.upload(ctx, directions);
  rays.radii.upload(ctx, radii);
  auto t = test::upload(ctx, t_edges, "t_edges");
  const size_t rows = n_rays * n_samples;
  const EncodingOptions options;
  for (auto shape : {RayShape::cone, RayShape::cylinder}) {
    INFO("ray shape " << static_cast<int>(shape));
    ocl::DeviceArray<float> means(ctx, 3 * rows, "means"), covs(ctx, 3 * rows, "covs");
    ocl::DeviceArray<float> separate(ctx, rows * 96, "separate"), fused(ctx, rows * 96, "fused");
    const ops::GaussianInputs in{rays, t, n_rays, n_samples};
    ops::Gaussian(ctx, {shape}).fwd(in, {means, covs});
    ops::Encode encode(ctx, {shape}, per_row_every(1));
    encode.ipe(options, {means, covs, rows}, separate);
    encode.gaussian_ipe(options, in, fused);
    // The same inline functions with contraction off (gaussian.cl): bit-identical, with either spread of the work.
    CHECK(fused.download(ctx) == separate.download(ctx));
    for (auto items : {ops::EncodeTuning::FusedItems::per_row, ops::EncodeTuning::FusedItems::per_row_and_degree}) {
      ops::EncodeTuning tuning;
      tuning.fused_items = items;
      tuning.sincos_every = 1;
      ops::Encode tuned(ctx, {shape}, tuning);
      CHECK(tuned.fused_per_row() == (items == ops::EncodeTuning::FusedItems::per_row));
      auto other = test::filled(ctx, rows * 96, 7.0f, "fused (tuned)");
      tuned.gaussian_ipe(options, in, other);
      CHECK(other.download(ctx) == separate.download(ctx));
    }
    // And both match the reference composition.
    std::vector<double> features;
    ref::gaussian_ipe_fwd({shape}, options, test::to_double(origins), test::to_double(directions),
                          test::to_double(radii), test::to_double(t_edges), features, n_rays, n_samples);
    // Here the float Gaussian's own error (≤ 12u of t_mean·|d| + 2u·|o|, see test_gaussian) is multiplied by 2^l
    // in the argument: the tolerance adds 2^l·|Δmean| to the feature tolerance (|d sin(y)/dy| ≤ 1), and the
    // variance error (≤ 35u relative) times 4^l·σ²/2 through the attenuation.
    const auto fused_values = fused.download(ctx);
    std::vector<double> means_ref, covs_ref;
    ref::gaussian_fwd({shape}, test::to_double(origins), test::to_double(directions), test::to_double(radii),
                      test::to_double(t_edges), means_ref, covs_ref, n_rays, n_samples);
    auto tolerance = [&](int sincos_every) {
      return [&, sincos_every](size_t i) {
        return fused_feature_tolerance(i, features, origins, means_ref, covs_ref, n_samples, sincos_every);
      };
    };
    MIPNERF_CHECK_CLOSE("gaussian_ipe features", fused_values, features, tolerance(1));
    // Angle doubling (IPE_SINCOS_EVERY = K): the same reference, the derived bound added, never more. Items per
    // (row, axis) with K = 1 too: their sin/cos and exp are the kernel's own (≤ 2 and 3 ulp, encode.cl), inside the
    // same bound.
    for (const auto items : row_and_axis_items(ctx)) {
      for (const int k : {1, 2, 4, 8}) {
        if (k == 1 && items == ops::EncodeTuning::FusedItems::per_row) continue;  // checked bit for bit above
        INFO("items " << items_name(items) << ", a sincos every " << k << " degrees");
        ops::Encode doubling(ctx, {shape}, items_every(items, k));
        REQUIRE(doubling.sincos_every() == k);
        REQUIRE(doubling.fused_items() == items);
        auto doubled = test::filled(ctx, rows * 96, 7.0f, "fused (doubling)");
        doubling.gaussian_ipe(options, in, doubled);
        const auto doubled_values = doubled.download(ctx);
        MIPNERF_CHECK_CLOSE("gaussian_ipe features by angle doubling", doubled_values, features, tolerance(k));
        size_t differ = 0;  // and it is a different computation: some features are not those of a sincos per degree
        for (size_t i = 0; i < doubled_values.size(); ++i) differ += doubled_values[i] != fused_values[i];
        CHECK(differ > 0);
      }
    }
  }
}

TEST_CASE("encode: angle doubling in float stays within its derived bound against long double (host mirror)") {
  // ref::encode_degrees<float> is the kernel's recurrence in float with glibc's sinf/cosf (< 1 ulp, inside the
  // 4 ulp the bound assumes); |y| up to 2^15·100, every degree of the paper's L = 16, K = 2, 4, 8.
  std::mt19937 rng(28);
  std::uniform_real_distribution<double> magnitude(-2.0, 2.0);
  for (const int k : {2, 4, 8}) {
    double worst_ratio = 0;
    for (int i = 0; i < 20000; ++i) {
      const float mean = static_cast<float>((i % 2 ? 1 : -1) * std::pow(10.0, magnitude(rng)));
      float s[16], c[16];
      ref::encode_degrees<float>(mean, 0.0f, 0, 16, k, s, c);
      for (int l = 0; l < 16; ++l) {
        long double want_s, want_c;
        ref::ipe_pair<long double>(mean, 0.0L, l, want_s, want_c);
        const double bound = ref::doubling_error_bound(l % k);
        const double error = static_cast<double>(std::max(std::abs(s[l] - want_s), std::abs(c[l] - want_c)));
        REQUIRE(std::isfinite(error));
        worst_ratio = std::max(worst_ratio, error / bound);
      }
    }
    INFO("K = " << k << ": worst error " << worst_ratio << " of the bound");
    if (std::getenv("MIPNERF_TEST_VERBOSE")) MESSAGE("K = " << k << ": worst error " << worst_ratio << " of the bound");
    CHECK(worst_ratio <= 1.0);
    CHECK(worst_ratio > 0.05);  // the bound is not vacuous: errors come within a factor 20 of it
  }
}

TEST_CASE("encode: the fused kernel's angle doubling at large arguments (up to 2^15 x 100) against long double") {
  // Rays along +x with radius 0: the y and z coordinates of every sample are the origin's exactly and their
  // variance is 0, so those features are bare sin/cos of 2^l·o: the kernel's doubling against long double, for the
  // device's own choice of K and for K = 4.
  auto& ctx = test::test_context();
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> magnitude(-2.0, 2.0);
  const size_t n_rays = test::batch_for_device(2000), n_samples = 2;
  std::vector<float> origins, directions, radii(n_rays, 0.0f), t_edges;
  for (size_t ray = 0; ray < n_rays; ++ray) {
    origins.push_back(0.5f);
    for (int a = 0; a < 2; ++a) {
      origins.push_back(static_cast<float>((ray % 2 ? 1 : -1) * std::pow(10.0, magnitude(rng))));
    }
    directions.insert(directions.end(), {1.0f, 0.0f, 0.0f});
    t_edges.insert(t_edges.end(), {1.0f, 1.5f, 2.0f});
  }
  ops::RayBundle rays(ctx, n_rays);
  rays.origins.upload(ctx, origins);
  rays.directions.upload(ctx, directions);
  rays.radii.upload(ctx, radii);
  auto t = test::upload(ctx, t_edges, "t_edges");
  const ops::GaussianInputs in{rays, t, n_rays, n_samples};
  const EncodingOptions options;
  ops::Encode device_default(ctx, {RayShape::cone});
  for (const auto items : row_and_axis_items(ctx))
    for (const int k : {device_default.sincos_every(), 4}) {
      INFO("items " << items_name(items) << ", a sincos every " << k << " degrees");
      ops::Encode encode(ctx, {RayShape::cone}, items_every(items, k));
      auto features = test::filled(ctx, n_rays * n_samples * 96, 7.0f, "features");
      encode.gaussian_ipe(options, in, features);
      const auto got = features.download(ctx);
      size_t failures = 0;
      double worst_ratio = 0;
      for (size_t row = 0; row < n_rays * n_samples; ++row) {
        for (int a = 1; a < 3; ++a) {
          const float o = origins[3 * (row / n_samples) + a];
          for (int l = 0; l < 16; ++l) {
            long double want_s, want_c;
            ref::ipe_pair<long double>(o, 0.0L, l, want_s, want_c);
            const double error = static_cast<double>(std::max(std::abs(got[row * 96 + 3 * l + a] - want_s),
                                                              std::abs(got[row * 96 + 48 + 3 * l + a] - want_c)));
            const double bound = ref::doubling_error_bound(l % k);
            worst_ratio = std::max(worst_ratio, error / bound);
            failures += !(error <= bound);
          }
        }
      }
      INFO("worst error " << worst_ratio << " of the bound");
      CHECK(failures == 0);
    }
}

TEST_CASE("encode: per (row, axis), sin and cos reduced in double are within 2 ulp for |y| up to 2^40") {
  // encode.cl derives ≤ 1.8 ulp for sincos_reduced_in_double over |y| < 2^40. Rays of direction 0 and radius 0 give
  // means equal to their origins and variance 0 (attenuation exp(0) = 1 exactly), so with a sincos every degree
  // each feature is the kernel's sin or cos of y = 2^l·o, compared here with long double of that exact float y.
  // Origins: ±10^[−3, 7.5] log-uniform (|y| up to 1e12 at degree 15), and the float whose y at degree 15 lies
  // closest to a multiple of π/2 in [π/4, 2^40) (an exhaustive search over every float: 2.19993846e10, |r| = 2.0e-9).
  auto& ctx = test::test_context();
  if (!ctx.device_info().has_fp64) {
    CHECK_THROWS(ops::Encode(ctx, {RayShape::cone}, items_every(ops::EncodeTuning::FusedItems::per_row_and_axis, 1)));
    return;
  }
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> magnitude(-3.0, 7.5);
  const size_t n_rays = test::batch_for_device(3000), n_samples = 1;
  std::vector<float> origins, directions(3 * n_rays, 0.0f), radii(n_rays, 0.0f), t_edges;
  for (size_t ray = 0; ray < n_rays; ++ray) {
    for (int a = 0; a < 3; ++a) {
      origins.push_back(static_cast<float>((ray % 2 ? 1 : -1) * std::pow(10.0, magnitude(rng))));
    }
    t_edges.insert(t_edges.end(), {1.0f, 2.0f});
  }
  origins[0] = std::ldexp(2.19993846e10f, -15);  // exact: a power-of-two scaling of the hardest argument
  REQUIRE(std::ldexp(static_cast<double>(origins[0]), 15) == static_cast<double>(2.19993846e10f));
  ops::RayBundle rays(ctx, n_rays);
  rays.origins.upload(ctx, origins);
  rays.directions.upload(ctx, directions);
  rays.radii.upload(ctx, radii);
  auto t = test::upload(ctx, t_edges, "t_edges");
  const EncodingOptions options;
  ops::Encode encode(ctx, {RayShape::cone}, items_every(ops::EncodeTuning::FusedItems::per_row_and_axis, 1));
  auto features = test::filled(ctx, n_rays * 96, 7.0f, "features");
  encode.gaussian_ipe(options, {rays, t, n_rays, n_samples}, features);
  const auto got = features.download(ctx);
  double worst_ulps = 0;
  size_t failures = 0, unlike_mirror = 0;
  for (size_t ray = 0; ray < n_rays; ++ray) {
    for (int a = 0; a < 3; ++a) {
      for (int l = 0; l < 16; ++l) {
        long double want[2];
        ref::ipe_pair<long double>(origins[3 * ray + a], 0.0L, l, want[0], want[1]);
        const float have[2] = {got[ray * 96 + 3 * l + a], got[ray * 96 + 48 + 3 * l + a]};
        float mirror[2];  // the host's copy of the same operations: bit for bit
        ref::sincos_reduced_in_double(std::ldexp(origins[3 * ray + a], l), &mirror[0], &mirror[1]);
        unlike_mirror += have[0] != mirror[0] || have[1] != mirror[1];
        for (int k = 0; k < 2; ++k) {
          REQUIRE(std::isfinite(have[k]));
          const float want_float = static_cast<float>(std::abs(want[k]));
          const double ulp = std::nextafter(want_float, INFINITY) - want_float;
          const double ulps = static_cast<double>(std::abs(have[k] - want[k])) / ulp;
          worst_ulps = std::max(worst_ulps, ulps);
          failures += !(ulps <= 2.0);
        }
      }
    }
  }
  if (std::getenv("MIPNERF_TEST_VERBOSE")) MESSAGE("worst error " << worst_ulps << " ulp");
  INFO("worst error " << worst_ulps << " ulp of the long-double sin/cos of the exact float argument");
  CHECK(failures == 0);
  CHECK(worst_ulps > 0.3);  // not vacuous: the kernel's values are not the long double's rounded
  CHECK(unlike_mirror == 0);
}
