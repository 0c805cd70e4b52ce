// mip-NeRF 360's contraction of Gaussians and ray warps, our reference (host/ref/contract.hpp) and kernels
// (kernels/contract.cl) against the official multinerf functions' own outputs (fixtures/multinerf_contract.json,
// written by make_contract_vectors.py): coord.contract and coord.track_linearize(contract, mean, cov) on full
// covariances inside the ball, on the unit sphere and one float ulp either side, at the origin and far out (|x| up to
// 1e30), with rank-1 covariances; the vector-Jacobian product of that map (jax.vjp) w.r.t. the mean and the covariance;
// coord.construct_ray_warps(jnp.reciprocal, near, far) for several (near, far), far = inf included; near = 0, where
// the official gives NaN and our wrapper refuses. The official math ran in float64.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "official_fixtures.hpp"
#include "ops/contract.hpp"
#include "ops/ray_bundle.hpp"
#include "ops/sample_intervals.hpp"
#include "ref/contract.hpp"
#include "ref/sample_intervals.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

io::Json contract_fixture() {
  return official::multinerf_fixture("multinerf_contract.json");
}

// A number, or the strings "inf", "-inf", "nan" the generator writes for non-finite values.
double contract_value(const io::Json& v) {
  if (v.is_number()) return v.get<double>();
  const std::string s = v.get<std::string>();
  if (s == "inf") return std::numeric_limits<double>::infinity();
  if (s == "-inf") return -std::numeric_limits<double>::infinity();
  REQUIRE(s == "nan");
  return std::numeric_limits<double>::quiet_NaN();
}

std::vector<double> contract_values(const io::Json& array) {
  std::vector<double> out;
  for (const auto& v : array) out.push_back(contract_value(v));
  return out;
}

// How a full 3x3 matrix's pairs (M_ij, M_ji) become the one stored off-diagonal number.
enum class PairAs {
  exact,    // an input: M_ij = M_ji required
  average,  // the official's output J Σ Jᵀ, symmetric up to its float64 rounding (two products in different orders)
  sum,      // a gradient w.r.t. the full matrix: the stored number feeds both entries
};

// Full 3x3 matrices [n][3][3] → diag [n][3] and off (xy, xz, yz) [n][3].
void contract_split_matrices(const std::vector<double>& full, std::vector<double>& diag, std::vector<double>& off,
                             PairAs pair_as) {
  const size_t n = full.size() / 9;
  diag.resize(3 * n);
  off.resize(3 * n);
  for (size_t row = 0; row < n; ++row) {
    const double* m = &full[9 * row];
    for (int i = 0; i < 3; ++i) diag[3 * row + i] = m[4 * i];
    int k = 0;
    for (const auto& pair : {std::pair{1, 3}, std::pair{2, 6}, std::pair{5, 7}}) {
      const int ij = pair.first, ji = pair.second;  // not a structured binding (clang, doctest's CHECK)
      if (pair_as == PairAs::exact) CHECK(m[ij] == m[ji]);
      off[3 * row + k++] = pair_as == PairAs::sum ? m[ij] + m[ji] : 0.5 * (m[ij] + m[ji]);
    }
  }
}

// (a + b)² N per row, the scale of J X J's rounding (host/ref/contract.cpp): the official's float64 J (jax.linearize
// of (2√m − 1)/m · x) cancels a + (b − a) like any matrix form, to ~1e-16 of this scale; 1e-13 holds it with room.
std::vector<double> contract_scale(const std::vector<double>& means, const std::vector<double>& diag,
                                   const std::vector<double>& off) {
  std::vector<double> scale(means.size() / 3);
  for (size_t row = 0; row < scale.size(); ++row) {
    const double r = std::max(1.0, std::hypot(means[3 * row], means[3 * row + 1], means[3 * row + 2]));
    const double a = (2 * r - 1) / (r * r), b = 1 / (r * r);
    double n = 0;
    for (int i = 0; i < 3; ++i) n += std::abs(diag[3 * row + i]) + 2 * std::abs(off[3 * row + i]);
    scale[row] = (a + b) * (a + b) * n;
  }
  return scale;
}

constexpr double kOfficialContractRelative = 1e-13;

}  // namespace

TEST_CASE("multinerf contract: contract and track_linearize, our reference and kernel") {
  const io::Json fixture = contract_fixture();
  const io::Json& g = fixture.at("gaussians");
  const auto means = official::flat(g.at("means"));
  const size_t rows = means.size() / 3;
  REQUIRE(rows >= 30);
  std::vector<double> covs, off, fn_covs, fn_off;
  contract_split_matrices(official::flat(g.at("covs"), {rows, 3, 3}), covs, off, PairAs::exact);
  contract_split_matrices(official::flat(g.at("fn_covs"), {rows, 3, 3}), fn_covs, fn_off, PairAs::average);
  const auto fn_means = official::flat(g.at("fn_means"), {rows, 3});
  OFFICIAL_CHECK_AGREES("official contract = track_linearize's mean", official::flat(g.at("contract")), fn_means,
                        official::constant_bound(0.0));
  const auto scale = contract_scale(means, covs, off);
  auto cov_bound = [&](size_t i) { return kOfficialContractRelative * scale[i / 3]; };

  std::vector<double> r_means, r_covs, r_off;
  ref::contract_gaussians_fwd(means, covs, off, r_means, r_covs, r_off, rows);
  // Means ≤ 2, a few roundings in either: 1e-14.
  OFFICIAL_CHECK_AGREES("reference means", r_means, fn_means, official::constant_bound(1e-14));
  OFFICIAL_CHECK_AGREES("reference covs", r_covs, fn_covs, cov_bound);
  OFFICIAL_CHECK_AGREES("reference cov_off", r_off, fn_off, cov_bound);

  auto& ctx = test::test_context();
  ops::ContractGaussians stage(ctx);
  auto m_dev = official::upload(ctx, official::as_float(means), "means");
  auto c_dev = official::upload(ctx, official::as_float(covs), "covs");
  auto o_dev = official::upload(ctx, official::as_float(off), "cov_off");
  ocl::DeviceArray<float> k_means(ctx, 3 * rows, "out_means"), k_covs(ctx, 3 * rows, "out_covs"),
      k_off(ctx, 3 * rows, "out_cov_off");
  stage.fwd({m_dev, c_dev, o_dev, rows}, {k_means, k_covs, k_off});
  // The kernel's float32 bound (host/ref/contract.cpp) plus the official's own float64 rounding.
  const auto bound = ref::contract_gaussians_fwd_float32_bound(means, covs, off, rows);
  OFFICIAL_CHECK_AGREES("kernel means", k_means.download(ctx), fn_means,
                        [&](size_t i) { return bound.means[i] + 1e-14; });
  OFFICIAL_CHECK_AGREES("kernel covs", k_covs.download(ctx), fn_covs,
                        [&](size_t i) { return bound.covs[i] + cov_bound(i); });
  OFFICIAL_CHECK_AGREES("kernel cov_off", k_off.download(ctx), fn_off,
                        [&](size_t i) { return bound.cov_off[i] + cov_bound(i); });
}

TEST_CASE("multinerf contract: the vector-Jacobian product of track_linearize(contract), reference and kernel") {
  const io::Json fixture = contract_fixture();
  const io::Json& g = fixture.at("gaussians");
  const auto means = official::flat(g.at("means"));
  const size_t rows = means.size() / 3;
  std::vector<double> covs, off, g_covs, g_off_full, d_covs, d_off;
  contract_split_matrices(official::flat(g.at("covs"), {rows, 3, 3}), covs, off, PairAs::exact);
  // The cotangent G of the output covariance (symmetric) weighs both entries of each pair: the stored off's upstream
  // gradient is 2 G_ij.
  contract_split_matrices(official::flat(g.at("d_fn_covs"), {rows, 3, 3}), g_covs, g_off_full, PairAs::exact);
  std::vector<double> g_off(g_off_full.size());
  for (size_t i = 0; i < g_off.size(); ++i) g_off[i] = 2 * g_off_full[i];
  contract_split_matrices(official::flat(g.at("d_covs"), {rows, 3, 3}), d_covs, d_off, PairAs::sum);
  const auto g_means = official::flat(g.at("d_fn_means"), {rows, 3});
  const auto d_means = official::flat(g.at("d_means"), {rows, 3});

  std::vector<double> r_means, r_covs, r_off;
  ref::contract_gaussians_bwd(means, covs, off, g_means, g_covs, g_off, r_means, r_covs, r_off, rows);
  // The same scales as the forward's for the covariance's gradient (J G J), and for the mean's the magnitude of its
  // terms (host/ref/contract.cpp: 2 (a + b)|g|₁ + 80 inv_r² (a + b) N_G N_Σ), at 1e-13 for the official's float64.
  const auto bwd_scale = ref::contract_gaussians_bwd_float32_bound(means, covs, off, g_means, g_covs, g_off, rows);
  const double to_float64 = kOfficialContractRelative / (100.0 * official::kU);  // the bound's 100 u → 1e-13
  std::vector<double> g_scale = contract_scale(means, g_covs, g_off_full);
  auto mean_bound = [&](size_t i) {
    if (bwd_scale.means[i] == 0) return 1e-14 * std::abs(g_means[i]);  // inside: a copy
    return bwd_scale.means[i] * to_float64;
  };
  OFFICIAL_CHECK_AGREES("reference d_means", r_means, d_means, mean_bound);
  OFFICIAL_CHECK_AGREES("reference d_covs", r_covs, d_covs, [&](size_t i) {
    return kOfficialContractRelative * g_scale[i / 3] + 1e-14 * std::abs(d_covs[i]);
  });
  OFFICIAL_CHECK_AGREES("reference d_cov_off", r_off, d_off, [&](size_t i) {
    return 2 * kOfficialContractRelative * g_scale[i / 3] + 1e-14 * std::abs(d_off[i]);
  });

  auto& ctx = test::test_context();
  ops::ContractGaussians stage(ctx);
  auto up = [&](const std::vector<double>& v, const char* name) {
    return official::upload(ctx, official::as_float(v), name);
  };
  auto m_dev = up(means, "means"), c_dev = up(covs, "covs"), o_dev = up(off, "cov_off");
  auto gm_dev = up(g_means, "d_out_means"), gc_dev = up(g_covs, "d_out_covs"), go_dev = up(g_off, "d_out_cov_off");
  ocl::DeviceArray<float> k_means(ctx, 3 * rows, "d_means"), k_covs(ctx, 3 * rows, "d_covs"),
      k_off(ctx, 3 * rows, "d_cov_off");
  stage.bwd({m_dev, c_dev, o_dev, rows}, {gm_dev, gc_dev, go_dev, rows}, {k_means, k_covs, k_off});
  // The covariance's derivative w.r.t. the mean jumps at the sphere (b′ = 0 inside, −2 outside), so the kernel must
  // take the official's branch: the fixture's points beside the sphere are 2–4 float ulps of |x|² away from 1, where
  // the kernel's float |x|² decides as the official's float64 one (a point within an ulp could go either way).
  OFFICIAL_CHECK_AGREES("kernel d_means", k_means.download(ctx), d_means,
                        [&](size_t i) { return bwd_scale.means[i] + mean_bound(i); });
  OFFICIAL_CHECK_AGREES("kernel d_covs", k_covs.download(ctx), d_covs, [&](size_t i) {
    return bwd_scale.covs[i] + kOfficialContractRelative * g_scale[i / 3] + 1e-14 * std::abs(d_covs[i]);
  });
  OFFICIAL_CHECK_AGREES("kernel d_cov_off", k_off.download(ctx), d_off, [&](size_t i) {
    return bwd_scale.cov_off[i] + 2 * kOfficialContractRelative * g_scale[i / 3] + 1e-14 * std::abs(d_off[i]);
  });
}

TEST_CASE("multinerf contract: construct_ray_warps(reciprocal), reference and kernel, far = inf included") {
  const io::Json fixture = contract_fixture();
  const io::Json& cases = fixture.at("ray_warps");
  REQUIRE(cases.size() == 5);
  auto& ctx = test::test_context();
  size_t infinite_far = 0;
  for (const auto& c : cases) {
    const double near = c.at("near").get<double>(), far = contract_value(c.at("far"));
    CAPTURE(near);
    CAPTURE(far);
    const auto t = contract_values(c.at("t")), s_of_t = contract_values(c.at("s_of_t"));
    const auto s = contract_values(c.at("s")), t_of_s = contract_values(c.at("t_of_s"));
    const auto dt_ds = contract_values(c.at("dt_ds"));
    std::vector<double> rs, rt, rd;
    ref::ray_warp_t_to_s(t, rs, near, far);
    ref::ray_warp_s_to_t(s, rt, rd, near, far);
    ops::RayWarp warp(ctx, static_cast<float>(near), static_cast<float>(far));
    auto t_dev = official::upload(ctx, official::as_float(t), "t"),
         s_dev = official::upload(ctx, official::as_float(s), "s");
    ocl::DeviceArray<float> ks_dev(ctx, t.size(), "s"), kt_dev(ctx, s.size(), "t"), kd_dev(ctx, s.size(), "dt_ds");
    warp.t_to_s(t_dev, ks_dev, t.size());
    warp.s_to_t(s_dev, kt_dev, kd_dev, s.size());
    const auto ks = ks_dev.download(ctx), kt = kt_dev.download(ctx), kd = kd_dev.download(ctx);
    // s = 1 with far = ∞: the official's t = ∞, and its jax.grad NaN (0·∞ in the reciprocal's derivative), where
    // dt/ds's limit is +∞, ours: checked here, then left out of the finite comparisons.
    std::vector<double> t_of_s_finite = t_of_s, dt_ds_finite = dt_ds;
    if (std::isinf(far)) {
      ++infinite_far;
      REQUIRE(s.back() == 1.0);
      CHECK(std::isinf(t_of_s.back()));
      CHECK(std::isnan(dt_ds.back()));
      CHECK(std::isinf(rt.back()));
      CHECK(std::isinf(kt.back()));
      CHECK(std::isinf(rd.back()));
      CHECK(std::isinf(kd.back()));
      t_of_s_finite.pop_back();
      dt_ds_finite.pop_back();
      CHECK(std::isinf(t.back()));  // t = ∞ → s = 1, compared below
    }
    // Reference: the official's (1/t − 1/near)/(1/far − 1/near) in float64 is off by ~1e-16 of 1/near /
    // (1/near − 1/far) ≤ 2 (these cases): 1e-14 absolute for s ∈ [0, 1]; s_to_t is the same formula (1e-14
    // relative); dt/ds also, amplified by κ = (far + near)/(far − near) ≤ 2.
    OFFICIAL_CHECK_AGREES("reference t_to_s", rs, s_of_t, official::constant_bound(1e-14));
    OFFICIAL_CHECK_AGREES("reference s_to_t", rt, t_of_s_finite, [&](size_t i) { return 1e-14 * t_of_s[i]; });
    OFFICIAL_CHECK_AGREES("reference dt_ds", rd, dt_ds_finite, [&](size_t i) { return 1e-14 * dt_ds[i]; });
    OFFICIAL_CHECK_AGREES("kernel t_to_s", ks, s_of_t, [&](size_t i) {
      return ref::ray_warp_t_to_s_float32_relative_bound() * std::abs(s_of_t[i]) + 1e-14;
    });
    OFFICIAL_CHECK_AGREES("kernel s_to_t", kt, t_of_s_finite, [&](size_t i) {
      return (ref::ray_warp_s_to_t_float32_relative_bound() + 1e-14) * t_of_s[i];
    });
    OFFICIAL_CHECK_AGREES("kernel dt_ds", kd, dt_ds_finite, [&](size_t i) {
      return (ref::ray_warp_dt_ds_float32_relative_bound(near, far) + 1e-14) * dt_ds[i];
    });
  }
  CHECK(infinite_far == 2);
}

TEST_CASE("multinerf contract: near = 0 makes the official warps NaN, and our wrapper refuses it") {
  const io::Json fixture = contract_fixture();
  const io::Json& z = fixture.at("ray_warps_near_zero");
  REQUIRE(z.at("near").get<double>() == 0.0);
  for (double s : contract_values(z.at("s_of_t"))) CHECK(std::isnan(s));
  auto& ctx = test::test_context();
  CHECK_THROWS_WITH_AS(ops::RayWarp(ctx, 0.0f, static_cast<float>(z.at("far").get<double>())),
                       doctest::Contains("set a near bound > 0"), Error);
}

// Proposal sampling's s → t for mip-NeRF 360 (RayDistance::reciprocal in sample_intervals.cl, the warp the training
// graph runs) against the official construct_ray_warps(reciprocal)'s s_to_t, every (near, far) of the fixture, far = ∞
// included: the same formula as ray_warp_s_to_t_of plus a clip to [near, far], within the same bound.
TEST_CASE("multinerf contract: proposal sampling's reciprocal s to t equals the official warp, reference and kernel") {
  const io::Json fixture = contract_fixture();
  const io::Json& cases = fixture.at("ray_warps");
  auto& ctx = test::test_context();
  std::vector<float> s_all, near, far;
  std::vector<double> official_t, s_double;
  size_t per_ray = 0;
  for (const auto& c : cases) {
    const auto s = contract_values(c.at("s")), t_of_s = contract_values(c.at("t_of_s"));
    per_ray = s.size();
    near.push_back(static_cast<float>(c.at("near").get<double>()));
    far.push_back(static_cast<float>(contract_value(c.at("far"))));
    for (size_t i = 0; i < s.size(); ++i) {
      s_all.push_back(static_cast<float>(s[i]));
      s_double.push_back(s[i]);
      official_t.push_back(t_of_s[i]);
    }
  }
  const size_t n_rays = near.size();
  ops::RayBundle rays(ctx, n_rays);
  rays.near.upload(ctx, near);
  rays.far.upload(ctx, far);
  auto s_device = official::upload(ctx, s_all, "s");
  ocl::DeviceArray<float> t_device(ctx, s_all.size(), "t");
  ops::SampleIntervals(ctx, RayDistance::reciprocal).s_to_t(s_device, rays, n_rays, per_ray, t_device);
  const auto t = t_device.download(ctx);
  size_t infinite = 0;
  for (size_t i = 0; i < t.size(); ++i) {
    const size_t ray = i / per_ray;
    INFO("near " << near[ray] << ", far " << far[ray] << ", s = " << s_double[i] << ": official t " << official_t[i]);
    const double ours = ref::ray_distance_s_to_t(RayDistance::reciprocal, s_double[i], near[ray], far[ray]);
    if (std::isinf(official_t[i])) {  // s = 1 with far = ∞
      ++infinite;
      CHECK(std::isinf(ours));
      CHECK(std::isinf(t[i]));
      continue;
    }
    CHECK(std::abs(ours - official_t[i]) <= 1e-14 * official_t[i]);
    CHECK(std::abs(t[i] - official_t[i]) <= (ref::ray_warp_s_to_t_float32_relative_bound() + 1e-14) * official_t[i]);
  }
  CHECK(infinite == 2);
}
