// The concatenated-PE variant (kernels/encode.cl gaussian_concat_pe_fwd, supplement §7): the full covariance it
// lifts against Monte Carlo, its features against the double reference on random and hard rays (cones and
// cylinders, axis-aligned and zero directions, tiny to huge frustums, far distances) within bounds derived from
// float32 rounding, the feature layout written out, and the specialisation: only an Encode asked for it builds it.
#include <doctest/doctest.h>

#include <cmath>

#include "kernel_checks.hpp"
#include "ops/encode.hpp"
#include "ref/encode.hpp"
#include "ref/gaussian.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;
using test::kUnitRoundoff;

namespace {

struct Rays {
  std::vector<float> origins, directions, radii, t_edges;
  size_t n_rays = 0, n_samples = 0;
};

// Random rays as the fused IPE test draws them, then hard ones: axis-aligned directions (zero off-diagonals), a zero
// direction (|d|² clamped to 1e-10), tiny and huge radii, and intervals far away and very thin.
Rays random_and_hard_rays(size_t n_samples) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> unit(0.0, 1.0), signed_unit(-1.0, 1.0);
  Rays r;
  r.n_samples = n_samples;
  auto add_ray = [&](const float o[3], const float d[3], float radius, double t_first, double width_lo,
                     double width_hi) {
    r.origins.insert(r.origins.end(), o, o + 3);
    r.directions.insert(r.directions.end(), d, d + 3);
    r.radii.push_back(radius);
    double t = t_first;
    float previous = -1;
    for (size_t k = 0; k <= n_samples; ++k) {
      float edge = static_cast<float>(t);
      if (edge <= previous) edge = std::nextafter(previous, INFINITY);  // a non-empty interval in float too
      r.t_edges.push_back(edge);
      previous = edge;
      t += test::log_uniform(rng, width_lo, width_hi);
    }
    ++r.n_rays;
  };
  for (int ray = 0; ray < 200; ++ray) {
    const float o[3] = {float(3 * signed_unit(rng)), float(3 * signed_unit(rng)), float(3 * signed_unit(rng))};
    const float d[3] = {float(signed_unit(rng)), float(signed_unit(rng)), float(signed_unit(rng))};
    add_ray(o, d, static_cast<float>(test::log_uniform(rng, 1e-4, 1e-2)), 2 + unit(rng), 1e-4, 0.1);
  }
  const float origin[3] = {0.5f, -1.0f, 2.0f};
  const float axis_x[3] = {1, 0, 0}, axis_y[3] = {0, -1, 0}, zero[3] = {0, 0, 0}, skew[3] = {0.3f, -1.2f, 0.5f};
  add_ray(origin, axis_x, 1e-3f, 2.0, 1e-3, 1e-2);
  add_ray(origin, axis_y, 1e-3f, 2.0, 1e-3, 1e-2);
  add_ray(origin, zero, 1e-3f, 2.0, 1e-3, 1e-2);
  add_ray(origin, skew, 1e-9f, 2.0, 1e-7, 1e-6);  // tiny frustums: nanometre radius, micrometre widths
  add_ray(origin, skew, 100.0f, 2.0, 0.5, 5.0);   // huge frustums
  add_ray(origin, skew, 1e-3f, 1e4, 1e-3, 1e-1);  // far away and thin
  return r;
}

std::vector<float> run_concat_pe(const GaussianOptions& gaussian, const EncodingOptions& options, const Rays& r) {
  auto& ctx = test::test_context();
  ops::RayBundle rays(ctx, r.n_rays);
  rays.origins.upload(ctx, r.origins);
  rays.directions.upload(ctx, r.directions);
  rays.radii.upload(ctx, r.radii);
  auto t = test::upload(ctx, r.t_edges, "t_edges");
  const size_t rows = r.n_rays * r.n_samples;
  auto features = test::filled(ctx, rows * options.concat_pe_width(), 7.0f, "concat_pe_features");
  ops::EncodeTuning tuning;
  tuning.concat_pe = true;
  ops::Encode(ctx, gaussian, tuning).gaussian_concat_pe(options, {rays, t, r.n_rays, r.n_samples}, features);
  return features.download(ctx);
}

// The paper's setting: mean degrees 0..11, covariance degrees 0..1: 72 + 24 = 96 features, IPE's width.
EncodingOptions paper_concat_pe() {
  EncodingOptions options;
  options.max_deg = 12;
  options.covariance_degrees = 2;
  return options;
}

// sign(x)·√|x| is monotone with |f(a) − f(b)| ≤ √(2|a − b|) everywhere, and ≤ |a − b|/√(|x|/2) when both are
// beyond |x|/2 of 0: the error of the signed root of a value known to within ±dx, plus the root's own rounding.
double signed_sqrt_error(double x, double dx) {
  const double magnitude = std::abs(x);
  const double through_root = magnitude > 2 * dx ? dx / std::sqrt(magnitude / 2) : std::sqrt(2 * dx);
  return std::min(through_root, std::sqrt(2 * dx)) + 2 * kUnitRoundoff * std::sqrt(magnitude);
}

}  // namespace

TEST_CASE("concat-pe: the full lifted covariance (off-diagonal too) matches Monte Carlo samples of the frustum") {
  // Points uniform in the cone's frustum, as the diagonal's Monte Carlo test draws them (test_gaussian.cpp).
  std::mt19937_64 rng(78);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double o[3] = {0.5, -1.0, 2.0}, t0 = 1.5, t1 = 2.5, radius = 0.2;
  const double dirs[2][3] = {{0.3, -1.2, 0.5}, {-0.7, 0.2, -1.9}};
  for (const auto& d : dirs) {
    const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    const double n[3] = {d[0] / len, d[1] / len, d[2] / len};
    // e1 = n × x̂ normalised, e2 = n × e1: an orthonormal basis of the plane ⟂ d.
    double e1[3] = {0, n[2], -n[1]};
    const double e1_len = std::sqrt(e1[1] * e1[1] + e1[2] * e1[2]);
    for (double& v : e1) v /= e1_len;
    const double e2[3] = {n[1] * e1[2] - n[2] * e1[1], n[2] * e1[0] - n[0] * e1[2], n[0] * e1[1] - n[1] * e1[0]};
    const size_t samples = 400000;
    double sum[3] = {0, 0, 0}, sum_xy[3][3] = {};
    for (size_t s = 0; s < samples; ++s) {
      const double t = std::cbrt(t0 * t0 * t0 + unit(rng) * (t1 * t1 * t1 - t0 * t0 * t0));
      const double rho = radius * t * std::sqrt(unit(rng)), theta = 2 * M_PI * unit(rng);
      double p[3];
      for (int a = 0; a < 3; ++a) p[a] = o[a] + t * d[a] + rho * (std::cos(theta) * e1[a] + std::sin(theta) * e2[a]);
      for (int a = 0; a < 3; ++a) {
        sum[a] += p[a];
        for (int b = 0; b < 3; ++b) sum_xy[a][b] += p[a] * p[b];
      }
    }
    double cov_mc[3][3];
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) cov_mc[a][b] = sum_xy[a][b] / samples - (sum[a] / samples) * (sum[b] / samples);
    }
    std::vector<double> means, diag, off;
    ref::gaussian_full_fwd({RayShape::cone}, {o[0], o[1], o[2]}, {d[0], d[1], d[2]}, {radius}, {t0, t1}, means, diag,
                           off, 1, 1);
    const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    for (int k = 0; k < 3; ++k) {
      const int a = pairs[k][0], b = pairs[k][1];
      // Standard error of a sample covariance ≤ √((σ_a²σ_b² + σ_ab²)/M)·1.5 (bounded coordinates); 5 of them.
      const double tol = 5 * 1.5 * std::sqrt((cov_mc[a][a] * cov_mc[b][b] + cov_mc[a][b] * cov_mc[a][b]) / samples);
      INFO("direction (" << d[0] << ", " << d[1] << ", " << d[2] << ") entry " << a << b << ": lifted " << off[k]
                         << " vs Monte Carlo " << cov_mc[a][b]);
      CHECK(std::abs(off[k] - cov_mc[a][b]) <= tol);
      CHECK(std::abs(off[k]) > 3 * tol);  // the off-diagonal is really there: dropping it would fail
    }
  }
}

TEST_CASE("concat-pe: features match the double reference on random and hard rays, cones and cylinders") {
  const Rays r = random_and_hard_rays(24);
  for (bool identity : {false, true}) {
    EncodingOptions options = paper_concat_pe();
    options.append_identity = identity;
    const size_t width = options.concat_pe_width(), id = identity ? 3 : 0, mean_pe = id + 72;
    REQUIRE(width == (identity ? 99u : 96u));
    for (auto shape : {RayShape::cone, RayShape::cylinder}) {
      INFO("ray shape " << static_cast<int>(shape) << ", identity " << identity);
      const auto dev = run_concat_pe({shape}, options, r);
      std::vector<double> features, means, diag, off;
      ref::gaussian_concat_pe_fwd({shape}, options, test::to_double(r.origins), test::to_double(r.directions),
                                  test::to_double(r.radii), test::to_double(r.t_edges), features, r.n_rays,
                                  r.n_samples);
      ref::gaussian_full_fwd({shape}, test::to_double(r.origins), test::to_double(r.directions),
                             test::to_double(r.radii), test::to_double(r.t_edges), means, diag, off, r.n_rays,
                             r.n_samples);
      MIPNERF_CHECK_CLOSE("concat_pe features", dev, features, [&](size_t i) {
        const size_t row = i / width, k = i % width, ray = row / r.n_samples;
        const float* o = &r.origins[0] + 3 * ray;
        // The float mean's error (test_gaussian: ≤ 2u·|o| + 12u·|t_mean·d|) per axis.
        auto mean_err = [&](size_t a) {
          return 2 * kUnitRoundoff * std::abs(double(o[a])) + 12 * kUnitRoundoff * std::abs(means[3 * row + a] - o[a]);
        };
        const double base = 32 * kUnitRoundoff * std::abs(features[i]) + 1e-37;  // sin/cos to 4 ulp, one product
        if (k < id) return base + mean_err(k);
        if (k < mean_pe) {  // PE of the mean: the argument 2^l·mean carries 2^l times the mean's error
          const size_t j = (k - id) % 36, l = j / 3, a = j % 3;
          return base + 2 * std::ldexp(1.0, static_cast<int>(l)) * mean_err(a);
        }
        // PE of sign(Σ_e)·√|Σ_e|: the moments are within 35u (test_gaussian), the lift adds a few roundings; the
        // off-diagonal t_var − r_var/|d|² may cancel, so its error is relative to the sum of the two terms.
        const size_t j = (k - mean_pe) % 12, l = j / 6, e = j % 6;
        const float* dir = &r.directions[0] + 3 * ray;
        const double d_mag_sq =
            std::max(1e-10, double(dir[0]) * dir[0] + double(dir[1]) * dir[1] + double(dir[2]) * dir[2]);
        const int axis_pairs[6][2] = {{0, 0}, {0, 1}, {0, 2}, {1, 1}, {1, 2}, {2, 2}};
        const int a = axis_pairs[e][0], b = axis_pairs[e][1];
        const double value = a == b ? diag[3 * row + a] : off[3 * row + (a == 0 ? b - 1 : 2)];
        double scale = std::abs(value);
        if (a != b) {
          const auto m = shape == RayShape::cone
                             ? ref::conical_frustum_moments<double>(
                                   r.t_edges[ray * (r.n_samples + 1) + row % r.n_samples],
                                   r.t_edges[ray * (r.n_samples + 1) + row % r.n_samples + 1], r.radii[ray])
                             : ref::cylinder_moments<double>(r.t_edges[ray * (r.n_samples + 1) + row % r.n_samples],
                                                             r.t_edges[ray * (r.n_samples + 1) + row % r.n_samples + 1],
                                                             r.radii[ray]);
          scale = (m.t_var + m.r_var / d_mag_sq) * std::abs(double(dir[a]) * dir[b]);
        }
        const double dx = 48 * kUnitRoundoff * scale;
        return base + 2 * std::ldexp(1.0, static_cast<int>(l)) * signed_sqrt_error(value, dx);
      });
    }
  }
}

TEST_CASE("concat-pe: the layout written out for one ray along x (zero off-diagonals)") {
  Rays r;
  r.n_rays = 1;
  r.n_samples = 1;
  r.origins = {0.25f, -0.5f, 1.0f};
  r.directions = {2.0f, 0.0f, 0.0f};
  r.radii = {0.01f};
  r.t_edges = {1.0f, 1.5f};
  EncodingOptions options;
  options.min_deg = 0;
  options.max_deg = 2;
  options.covariance_degrees = 2;
  const auto dev = run_concat_pe({RayShape::cone}, options, r);
  REQUIRE(dev.size() == 12u + 24u);
  const auto m = ref::conical_frustum_moments<double>(1.0, 1.5, 0.01);
  const double mean[3] = {0.25 + 2 * m.t_mean, -0.5, 1.0};
  const double sigma[6] = {m.t_var * 4, 0, 0, m.r_var, 0, m.r_var};  // xx, xy, xz, yy, yz, zz
  for (int l = 0; l < 2; ++l) {
    for (int a = 0; a < 3; ++a) {
      CHECK(dev[3 * l + a] == doctest::Approx(std::sin(std::ldexp(mean[a], l))).epsilon(1e-5));
      CHECK(dev[6 + 3 * l + a] == doctest::Approx(std::cos(std::ldexp(mean[a], l))).epsilon(1e-5));
    }
    for (int e = 0; e < 6; ++e) {
      const double root = std::sqrt(sigma[e]);
      INFO("degree " << l << " element " << e);
      CHECK(dev[12 + 6 * l + e] == doctest::Approx(std::sin(std::ldexp(root, l))).epsilon(1e-5));
      CHECK(dev[24 + 6 * l + e] == doctest::Approx(std::cos(std::ldexp(root, l))).epsilon(1e-5));
    }
  }
  // The off-diagonals are exactly 0 (sign(0) = 0): sin 0 = 0 and cos 0 = 1, exactly.
  for (int l = 0; l < 2; ++l) {
    for (int e : {1, 2, 4}) {
      CHECK(dev[12 + 6 * l + e] == 0.0f);
      CHECK(dev[24 + 6 * l + e] == 1.0f);
    }
  }
}

TEST_CASE("concat-pe: only an Encode asked for it builds the kernel, and others refuse the call by name") {
  auto& ctx = test::test_context();
  Rays r;
  r.n_rays = 1;
  r.n_samples = 1;
  r.origins = {0, 0, 0};
  r.directions = {0, 0, 1};
  r.radii = {0.01f};
  r.t_edges = {1.0f, 2.0f};
  ops::RayBundle rays(ctx, 1);
  rays.origins.upload(ctx, r.origins);
  rays.directions.upload(ctx, r.directions);
  rays.radii.upload(ctx, r.radii);
  auto t = test::upload(ctx, r.t_edges, "t_edges");
  auto features = test::filled(ctx, 96, 7.0f, "features");
  ops::Encode plain(ctx, {});
  CHECK_THROWS_WITH_AS(plain.gaussian_concat_pe(paper_concat_pe(), {rays, t, 1, 1}, features),
                       doctest::Contains("built without the concatenated-PE kernel"), Error);
  ops::EncodeTuning tuning;
  tuning.concat_pe = true;
  ops::Encode with_concat(ctx, {}, tuning);
  EncodingOptions no_covariance = paper_concat_pe();
  no_covariance.covariance_degrees = 0;
  CHECK_THROWS_WITH_AS(with_concat.gaussian_concat_pe(no_covariance, {rays, t, 1, 1}, features),
                       doctest::Contains("covariance_degrees = 0"), Error);
  auto short_features = test::filled(ctx, 95, 7.0f, "short_features");
  CHECK_THROWS_WITH_AS(with_concat.gaussian_concat_pe(paper_concat_pe(), {rays, t, 1, 1}, short_features),
                       doctest::Contains("short_features"), Error);
}
