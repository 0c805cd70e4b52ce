// Frustum/cylinder Gaussians (kernels/gaussian.cl): against the double reference, frustum moments over six decades
// of distance and seven of width against a long-double quadrature of the frustum, the naive eqs. 20–22 failing
// where the stable eq. 23 holds, rays exactly along an axis, a zero direction and a zero radius, the lifted
// covariance against Monte Carlo, and NeRF's point samples.
#include <doctest/doctest.h>

#include <array>

#include "kernel_checks.hpp"
#include "ops/gaussian.hpp"
#include "ref/gaussian.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;
using test::kUnitRoundoff;

namespace {

struct Rays {
  size_t n_rays = 0, n_samples = 0;
  std::vector<float> origins, directions, radii, t_edges;
};

// Origins in [−3, 3]³, directions of norm 0.5..2 (a fifth of them within 1e-3 of a coordinate axis, where
// 1 − d²/|d|² cancels in the official form), radii 1e-4..1e-1, edges from 0.05..2 with gaps log-uniform over
// 1e-6..0.5 and some empty intervals.
Rays random_rays(size_t n_rays, size_t n_samples, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0), signed_unit(-1.0, 1.0);
  Rays r;
  r.n_rays = n_rays;
  r.n_samples = n_samples;
  for (size_t ray = 0; ray < n_rays; ++ray) {
    for (int a = 0; a < 3; ++a) r.origins.push_back(static_cast<float>(3 * signed_unit(rng)));
    std::array<double, 3> d = {signed_unit(rng), signed_unit(rng), signed_unit(rng)};
    if (ray % 5 == 0) {
      const size_t axis = ray / 5 % 3;
      for (size_t a = 0; a < 3; ++a) d[a] = a == axis ? 1.0 : 1e-3 * signed_unit(rng);
    }
    const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]), norm = 0.5 + 1.5 * unit(rng);
    for (double v : d) r.directions.push_back(static_cast<float>(v / len * norm));
    r.radii.push_back(static_cast<float>(test::log_uniform(rng, 1e-4, 1e-1)));
    float t = static_cast<float>(0.05 + 2 * unit(rng));
    r.t_edges.push_back(t);
    for (size_t i = 0; i < n_samples; ++i) {
      if (unit(rng) > 0.03) t += static_cast<float>(test::log_uniform(rng, 1e-6, 0.5));
      r.t_edges.push_back(t);
    }
  }
  return r;
}

struct Gaussians {
  std::vector<float> means, covs;
};

Gaussians run_device(const GaussianOptions& options, const Rays& r, bool points = false,
                     ops::GaussianItems items = ops::GaussianItems::device_default) {
  auto& ctx = test::test_context();
  ops::RayBundle rays(ctx, r.n_rays);
  rays.origins.upload(ctx, r.origins);
  rays.directions.upload(ctx, r.directions);
  rays.radii.upload(ctx, r.radii);
  auto t_edges = test::upload(ctx, r.t_edges, "t_edges");
  const size_t rows = r.n_rays * r.n_samples;
  auto means = test::filled(ctx, 3 * rows, 7.0f, "means"), covs = test::filled(ctx, 3 * rows, 7.0f, "covs");
  ops::Gaussian stage(ctx, options, items);
  REQUIRE((items == ops::GaussianItems::device_default || stage.items() == items));
  const ops::GaussianInputs in{rays, t_edges, r.n_rays, r.n_samples};
  if (points) {
    stage.points(in, {means, covs});
  } else {
    stage.fwd(in, {means, covs});
  }
  return {means.download(ctx), covs.download(ctx)};
}

// The moments of the conical frustum {t ∈ [t0, t1], radius r·t}, from their definition rather than eq. 23:
// along the axis t has density ∝ t² (the disc area), so with t = μ + h·x, x ∈ [−1, 1],
//   E[t] = ∫(μ + hx)³ / ∫(μ + hx)²,  Var t = ∫(hx − δ)²(μ + hx)² / ∫(μ + hx)² with δ = E[t] − μ,
//   r_var = r²/4·∫(μ + hx)⁴ / ∫(μ + hx)²   (a uniform disc of radius ρ has per-axis variance ρ²/4).
// The integrands are polynomials of degree ≤ 4, which 3-point Gauss–Legendre integrates exactly; δ is integrated
// directly (its odd part) so nothing cancels. Long double throughout.
ref::FrustumMoments<long double> frustum_moments_quadrature(long double t0, long double t1, long double radius) {
  const long double node = std::sqrt(0.6L), nodes[3] = {-node, 0.0L, node};
  const long double weights[3] = {5.0L / 9, 8.0L / 9, 5.0L / 9};
  const long double mu = (t0 + t1) / 2, h = (t1 - t0) / 2;
  long double m2 = 0, odd = 0, m4 = 0;
  for (int i = 0; i < 3; ++i) {
    const long double t = mu + h * nodes[i];
    m2 += weights[i] * t * t;
    odd += weights[i] * h * nodes[i] * t * t;
    m4 += weights[i] * t * t * t * t;
  }
  const long double shift = odd / m2;
  long double var = 0;
  for (int i = 0; i < 3; ++i) {
    const long double t = mu + h * nodes[i], dx = h * nodes[i] - shift;
    var += weights[i] * dx * dx * t * t;
  }
  return {mu + shift, var / m2, radius * radius / 4 * m4 / m2};
}

double relative_error(double value, long double truth) {
  return static_cast<double>(std::abs((static_cast<long double>(value) - truth) / truth));
}

// Thin-to-wide frustums: t0 = 10^k (k = −1..4), t1 − t0 = 10^m·t0 (m = −7..0 in half decades), as floats.
struct Frustum {
  float t0, t1;
  int half_decades;  // m = half_decades / 2: the nominal width is 10^m·t0
};
std::vector<Frustum> hard_frustums() {
  std::vector<Frustum> out;
  for (int k = -1; k <= 4; ++k) {
    for (int half = -14; half <= 0; ++half) {
      const double t0 = std::pow(10.0, k), width = std::pow(10.0, half / 2.0) * t0;
      const float t0f = static_cast<float>(t0);
      float t1f = static_cast<float>(t0 + width);
      if (t1f == t0f) t1f = std::nextafter(t0f, INFINITY);  // keep every frustum non-empty
      out.push_back({t0f, t1f, half});
    }
  }
  return out;
}

// Rays exactly along ±x, ±y, ±z (unit and longer), a zero direction and random directions, each with radius 0,
// 1e-3 and 0.1; edges from 0 (a first interval [0, 0], then [0, t]) or from 0.05..2, with some empty intervals.
Rays axis_zero_and_zero_radius_rays(size_t n_samples, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0), signed_unit(-1.0, 1.0);
  const std::vector<std::array<float, 3>> fixed = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0}, {0, -1, 0},    {0, 0, 1},
                                                   {0, 0, -1}, {0, 0, -2}, {3, 0, 0}, {0, -0.5f, 0}, {0, 0, 0}};
  Rays r;
  r.n_samples = n_samples;
  for (int copy = 0; copy < 12; ++copy) {
    for (size_t k = 0; k < fixed.size() + 2; ++k) {
      for (float radius : {0.0f, 1e-3f, 0.1f}) {
        for (int a = 0; a < 3; ++a) r.origins.push_back(static_cast<float>(3 * signed_unit(rng)));
        for (int a = 0; a < 3; ++a) {
          r.directions.push_back(k < fixed.size() ? fixed[k][a] : static_cast<float>(signed_unit(rng)));
        }
        r.radii.push_back(radius);
        const bool from_zero = copy % 3 == 0;
        float t = from_zero ? 0.0f : static_cast<float>(0.05 + 2 * unit(rng));
        r.t_edges.push_back(t);
        for (size_t i = 0; i < n_samples; ++i) {
          const bool empty = (from_zero && i == 0) || unit(rng) < 0.1;
          if (!empty) t += static_cast<float>(test::log_uniform(rng, 1e-6, 0.5));
          r.t_edges.push_back(t);
        }
        ++r.n_rays;
      }
    }
  }
  return r;
}

// The tolerances of the first test below (its comment derives them): per element, twice the float32 bound of the
// mean (2u·|o_a| + 12u·|t_mean·d_a|) and of the covariance (35u of its two non-negative terms).
void gaussian_tolerances(RayShape shape, const Rays& r, std::vector<double>& mean_tol, std::vector<double>& cov_tol) {
  const size_t rows = r.n_rays * r.n_samples;
  mean_tol.assign(3 * rows, 0.0);
  cov_tol.assign(3 * rows, 0.0);
  for (size_t ray = 0; ray < r.n_rays; ++ray) {
    const double d[3] = {r.directions[3 * ray], r.directions[3 * ray + 1], r.directions[3 * ray + 2]};
    const double d_sq = std::max(1e-10, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (size_t i = 0; i < r.n_samples; ++i) {
      const double t0 = r.t_edges[ray * (r.n_samples + 1) + i], t1 = r.t_edges[ray * (r.n_samples + 1) + i + 1];
      const auto m = shape == RayShape::cone ? ref::conical_frustum_moments(t0, t1, double(r.radii[ray]))
                                             : ref::cylinder_moments(t0, t1, double(r.radii[ray]));
      for (int a = 0; a < 3; ++a) {
        const size_t at = 3 * (ray * r.n_samples + i) + a;
        mean_tol[at] =
            2 * (2 * kUnitRoundoff * std::abs(r.origins[3 * ray + a]) + 12 * kUnitRoundoff * std::abs(m.t_mean * d[a]));
        cov_tol[at] = 2 * 35 * kUnitRoundoff * (m.t_var * d[a] * d[a] + m.r_var * (1 - d[a] * d[a] / d_sq)) + 1e-44;
      }
    }
  }
}

}  // namespace

TEST_CASE("gaussian: cone and cylinder Gaussians match the CPU reference on 12,800 random intervals") {
  const Rays r = random_rays(200, 64, 31);
  for (auto shape : {RayShape::cone, RayShape::cylinder}) {
    INFO("ray shape " << static_cast<int>(shape));
    const GaussianOptions options{shape};
    const auto dev = run_device(options, r);
    std::vector<double> means, covs;
    ref::gaussian_fwd(options, test::to_double(r.origins), test::to_double(r.directions), test::to_double(r.radii),
                      test::to_double(r.t_edges), means, covs, r.n_rays, r.n_samples);
    // Tolerances (gaussian_tolerances). t_mean = t_μ·(1 + 2·ratio) is ≤ 10 roundings (two sums, squares, the
    // 2.5-ulp division) of itself, so mean_a = o_a + t_mean·d_a is within 2u·|o_a| + 12u·|t_mean·d_a|. The
    // variances: the bracket of t_var, 1/3 − (4/15)·ratio·q ∈ [3/20, 1/3], amplifies the ~15u error of ratio·q by at
    // most 11/9, so t_var (and r_var likewise) carry ≤ 25u; d²/|d|² written as (d_b² + d_c²)/|d|² adds ≤ 8u without
    // cancellation. So |Δcov_a| ≤ 35u·(t_var·d_a² + r_var·(1 − d_a²/|d|²)). Tolerances are twice these bounds.
    std::vector<double> mean_scale, cov_scale;
    gaussian_tolerances(shape, r, mean_scale, cov_scale);
    MIPNERF_CHECK_CLOSE("means", dev.means, means, [&](size_t i) { return mean_scale[i]; });
    MIPNERF_CHECK_CLOSE("covs", dev.covs, covs, [&](size_t i) { return cov_scale[i]; });
  }
}

TEST_CASE("gaussian: an item per 16 samples gives the per-row Gaussians bit for bit, with shorter last runs") {
  // 37 samples per ray: two runs of 16 as float16, then 5 samples row by row; the same operations per lane as the
  // per-row kernel (gaussian.cl), so the same floats.
  const Rays r = random_rays(120, 37, 36);
  for (auto shape : {RayShape::cone, RayShape::cylinder}) {
    INFO("ray shape " << static_cast<int>(shape));
    const auto per_row = run_device({shape}, r, false, ops::GaussianItems::per_row);
    const auto per_vector = run_device({shape}, r, false, ops::GaussianItems::per_vector);
    CHECK(per_vector.means == per_row.means);
    CHECK(per_vector.covs == per_row.covs);
  }
}

TEST_CASE("gaussian: rays along an axis, a zero direction and a zero radius give the reference's Gaussians") {
  // Radius exactly 0 (a cone or cylinder of zero width) leaves only the spread along the ray, t_var·d²; a
  // direction exactly along an axis makes the other two components of the mean the origin's and of the covariance
  // r_var (d_a² = 0, (d_b² + d_c²)/|d|² = 1, both exact); a zero direction is the reference's definition: mean = o,
  // covariance 0 (|d|² clamped to 1e-10 as officially, then 0/1e-10; the official 1 − d²/|d|² gives r_var there).
  const Rays r = axis_zero_and_zero_radius_rays(16, 35);
  for (auto shape : {RayShape::cone, RayShape::cylinder}) {
    INFO("ray shape " << static_cast<int>(shape));
    const GaussianOptions options{shape};
    const auto dev = run_device(options, r);
    std::vector<double> means, covs;
    ref::gaussian_fwd(options, test::to_double(r.origins), test::to_double(r.directions), test::to_double(r.radii),
                      test::to_double(r.t_edges), means, covs, r.n_rays, r.n_samples);
    std::vector<double> mean_tol, cov_tol;
    gaussian_tolerances(shape, r, mean_tol, cov_tol);
    MIPNERF_CHECK_CLOSE("means (axes, zero direction, zero radius)", dev.means, means,
                        [&](size_t i) { return mean_tol[i]; });
    MIPNERF_CHECK_CLOSE("covs (axes, zero direction, zero radius)", dev.covs, covs,
                        [&](size_t i) { return cov_tol[i]; });
    size_t exact_zero_covs = 0;
    for (size_t row = 0; row < r.n_rays * r.n_samples; ++row) {
      const size_t ray = row / r.n_samples;
      const float* d = &r.directions[3 * ray];
      for (int a = 0; a < 3; ++a) {
        if (d[a] != 0.0f) continue;
        // o_a + t_mean·0 and, with radius 0, t_var·0 + 0·(…): exact in float32 as in the reference.
        REQUIRE(dev.means[3 * row + a] == r.origins[3 * ray + a]);
        if (r.radii[ray] == 0.0f || (d[0] == 0.0f && d[1] == 0.0f && d[2] == 0.0f)) {
          REQUIRE(dev.covs[3 * row + a] == 0.0f);
          ++exact_zero_covs;
        }
      }
    }
    CHECK(exact_zero_covs > 1000);  // the cases are really there
  }
}

TEST_CASE("gaussian: frustum moments stay accurate from t0 = 0.1 to 1e4 and widths 1e-7 to 1 of t0") {
  const auto frustums = hard_frustums();
  Rays r;
  r.n_rays = frustums.size();
  r.n_samples = 1;
  for (const auto& f : frustums) {
    // o = 0, d = (0, 0, 1), radius 1: mean_z = t_mean, cov = (r_var, r_var, t_var) exactly (d² and 1 − d²/|d|²
    // are 0 or 1), so the kernel's float moments are read back unchanged.
    r.origins.insert(r.origins.end(), {0.0f, 0.0f, 0.0f});
    r.directions.insert(r.directions.end(), {0.0f, 0.0f, 1.0f});
    r.radii.push_back(1.0f);
    r.t_edges.insert(r.t_edges.end(), {f.t0, f.t1});
  }
  const auto dev = run_device({RayShape::cone}, r);
  double worst[3] = {0, 0, 0}, worst_ref = 0;
  for (size_t i = 0; i < frustums.size(); ++i) {
    const auto& f = frustums[i];
    const auto truth = frustum_moments_quadrature(f.t0, f.t1, 1.0L);
    const double got[3] = {dev.means[3 * i + 2], dev.covs[3 * i + 2], dev.covs[3 * i]};
    const long double want[3] = {truth.t_mean, truth.t_var, truth.r_var};
    for (int q = 0; q < 3; ++q) {
      REQUIRE(std::isfinite(got[q]));
      worst[q] = std::max(worst[q], relative_error(got[q], want[q]));
    }
    // Eq. 23 itself, in long double, agrees with the quadrature (an independent derivation of the same moments).
    const auto eq23 = ref::conical_frustum_moments<long double>(f.t0, f.t1, 1.0L);
    worst_ref = std::max({worst_ref, relative_error(static_cast<double>(eq23.t_mean), truth.t_mean),
                          relative_error(static_cast<double>(eq23.t_var), truth.t_var),
                          relative_error(static_cast<double>(eq23.r_var), truth.r_var)});
  }
  if (std::getenv("MIPNERF_TEST_VERBOSE")) {
    MESSAGE("worst relative errors: t_mean " << worst[0] << ", t_var " << worst[1] << ", r_var " << worst[2]
                                             << "; eq. 23 in long double " << worst_ref);
  }
  INFO("worst relative error of the float32 kernel: t_mean " << worst[0] << ", t_var " << worst[1] << ", r_var "
                                                             << worst[2] << "; eq. 23 in long double " << worst_ref);
  // ≤ 10u for t_mean and ≤ 25u for the variances (see the previous test): 1e-6 ≈ 17u covers t_mean with margin,
  // 3e-6 ≈ 50u the variances.
  CHECK(worst[0] <= 1e-6);
  CHECK(worst[1] <= 3e-6);
  CHECK(worst[2] <= 3e-6);
  CHECK(worst_ref <= 1e-12);  // double-rounded long double inputs; 1e-12 is far above long double's 1e-19
}

TEST_CASE("gaussian: the naive moments (supplement eqs. 20-22) fail in float32 where the stable form holds") {
  size_t naive_failures = 0, thin_cases = 0;
  double stable_worst = 0;
  for (const auto& f : hard_frustums()) {
    const auto truth = frustum_moments_quadrature(f.t0, f.t1, 1.0L);
    const auto naive = ref::conical_frustum_moments_naive<float>(f.t0, f.t1, 1.0f);
    const auto stable = ref::conical_frustum_moments<float>(f.t0, f.t1, 1.0f);
    stable_worst = std::max({stable_worst, relative_error(stable.t_mean, truth.t_mean),
                             relative_error(stable.t_var, truth.t_var), relative_error(stable.r_var, truth.r_var)});
    // Thin frustums (nominal width ≤ 1e-3·t0): the naive variance subtracts two numbers that agree to ~7 digits.
    if (f.half_decades <= -6) {
      ++thin_cases;
      const bool failed = !std::isfinite(naive.t_var) || relative_error(naive.t_var, truth.t_var) > 0.1;
      if (failed) ++naive_failures;
    }
  }
  INFO("naive t_var off by more than 10% in " << naive_failures << " of " << thin_cases
                                              << " thin frustums; stable worst relative error " << stable_worst);
  if (std::getenv("MIPNERF_TEST_VERBOSE")) {
    MESSAGE("naive failures " << naive_failures << " of " << thin_cases << "; stable worst " << stable_worst);
  }
  CHECK(thin_cases == 6 * 9);
  CHECK(naive_failures == thin_cases);  // every thin frustum: the naive form is useless there
  CHECK(stable_worst <= 3e-6);          // the same formulas on the host in float: as accurate as the kernel
}

TEST_CASE("gaussian: the lifted mean and covariance match Monte Carlo samples of the frustum") {
  // Points uniform in the frustum {o + t·d + ρ·(cos θ·e1 + sin θ·e2)}, t ∈ [t0, t1] with density ∝ t², ρ ≤ r·t
  // uniform over the disc; e1, e2 span the plane ⟂ d.
  std::mt19937_64 rng(77);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Rays r;
  r.n_rays = 3;
  r.n_samples = 1;
  const double dirs[3][3] = {{0.3, -1.2, 0.5}, {1.0, 0.0, 0.0}, {-0.7, 0.2, -1.9}};
  for (size_t ray = 0; ray < r.n_rays; ++ray) {
    r.origins.insert(r.origins.end(), {0.5f, -1.0f, 2.0f});
    for (double v : dirs[ray]) r.directions.push_back(static_cast<float>(v));
    r.radii.push_back(0.2f);
    r.t_edges.insert(r.t_edges.end(), {1.5f, 2.5f});
  }
  const auto dev = run_device({RayShape::cone}, r);
  const size_t samples = 400000;
  for (size_t ray = 0; ray < r.n_rays; ++ray) {
    double d[3], e1[3], e2[3];
    for (int a = 0; a < 3; ++a) d[a] = r.directions[3 * ray + a];
    const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    const double n[3] = {d[0] / len, d[1] / len, d[2] / len};
    const double helper[3] = {std::abs(n[0]) < 0.9 ? 1.0 : 0.0, std::abs(n[0]) < 0.9 ? 0.0 : 1.0, 0.0};
    e1[0] = helper[1] * n[2] - helper[2] * n[1];
    e1[1] = helper[2] * n[0] - helper[0] * n[2];
    e1[2] = helper[0] * n[1] - helper[1] * n[0];
    const double e1_len = std::sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    for (double& v : e1) v /= e1_len;
    e2[0] = n[1] * e1[2] - n[2] * e1[1];
    e2[1] = n[2] * e1[0] - n[0] * e1[2];
    e2[2] = n[0] * e1[1] - n[1] * e1[0];
    const double t0 = 1.5, t1 = 2.5, radius = 0.2;
    double sum[3] = {0, 0, 0}, sum_sq[3] = {0, 0, 0};
    for (size_t s = 0; s < samples; ++s) {
      const double t = std::cbrt(t0 * t0 * t0 + unit(rng) * (t1 * t1 * t1 - t0 * t0 * t0));
      const double rho = radius * t * std::sqrt(unit(rng)), theta = 2 * M_PI * unit(rng);
      for (int a = 0; a < 3; ++a) {
        const double p = r.origins[3 * ray + a] + t * d[a] + rho * (std::cos(theta) * e1[a] + std::sin(theta) * e2[a]);
        sum[a] += p;
        sum_sq[a] += p * p;
      }
    }
    for (int a = 0; a < 3; ++a) {
      const double mean = sum[a] / samples, var = sum_sq[a] / samples - mean * mean;
      // Monte Carlo standard errors: sqrt(var/M) for the mean, ≤ sqrt(2/M)·var·1.5 for the variance (the
      // kurtosis of these bounded coordinates is below 3); 5 standard errors, fixed seed.
      const double mean_tol = 5 * std::sqrt(var / samples), var_tol = 5 * 1.5 * std::sqrt(2.0 / samples) * var + 1e-9;
      INFO("ray " << ray << " axis " << a << ": kernel mean " << dev.means[3 * ray + a] << " vs " << mean
                  << ", kernel var " << dev.covs[3 * ray + a] << " vs " << var);
      CHECK(std::abs(dev.means[3 * ray + a] - mean) <= mean_tol);
      CHECK(std::abs(dev.covs[3 * ray + a] - var) <= var_tol);
    }
  }
}

TEST_CASE("gaussian: point samples sit at interval midpoints with zero covariance") {
  const Rays r = random_rays(200, 64, 41);
  const auto dev = run_device({RayShape::cone}, r, true);
  std::vector<double> means, covs;
  ref::gaussian_points_fwd(test::to_double(r.origins), test::to_double(r.directions), test::to_double(r.t_edges), means,
                           covs, r.n_rays, r.n_samples);
  // mean_a = o_a + t_mid·d_a: t_mid is one sum and a halving (exact), then a product and a sum: ≤ 3u of the terms.
  MIPNERF_CHECK_CLOSE("means", dev.means, means, [&](size_t i) {
    const size_t ray = i / 3 / r.n_samples, a = i % 3;
    const double t_far = r.t_edges[(ray + 1) * (r.n_samples + 1) - 1];
    return 2 * 3 * kUnitRoundoff * (std::abs(r.origins[3 * ray + a]) + t_far * std::abs(r.directions[3 * ray + a]));
  });
  for (float c : dev.covs) REQUIRE(c == 0.0f);
}

TEST_CASE("gaussian: undersized buffers are refused with the buffer's name") {
  auto& ctx = test::test_context();
  ops::RayBundle rays(ctx, 2);
  ocl::DeviceArray<float> t_edges(ctx, 2 * 5, "t_edges"), means(ctx, 3 * 8, "means"), covs(ctx, 3 * 7, "covs [short]");
  ops::Gaussian stage(ctx, {});
  CHECK_THROWS_WITH_AS(stage.fwd({rays, t_edges, 2, 4}, {means, covs}), doctest::Contains("covs [short]"), Error);
}
