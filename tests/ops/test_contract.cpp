// mip-NeRF 360's contraction of Gaussians and its ray warps (kernels/contract.cl) against the double reference
// (host/ref/contract.hpp, which tests/official/test_contract.cpp pins to multinerf): the reference against an
// independent oracle (the explicit Jacobian matrix in long double), the Jacobian's continuity across the unit sphere,
// the kernels' forward and backward against the reference under the derived float32 bounds (a 0.1% change of |x| fails
// them) on hard cases (|x| up to 3e38, where |x|² overflows float32; on the sphere and one ulp either side; x = 0;
// rank-1 and diagonal covariances), the backward against finite differences on the reference and on the kernel, and
// the reciprocal ray warps (far = ∞ included; near = 0 refused).
#include <doctest/doctest.h>

#include <array>
#include <cfloat>
#include <cmath>
#include <limits>
#include <random>

#include "core/error.hpp"
#include "kernel_checks.hpp"
#include "ops/contract.hpp"
#include "ref/contract.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;
using test::kUnitRoundoff;

namespace {

struct ContractBatch {
  std::vector<float> means, covs, off;
  size_t rows = 0;
};

enum class CovKind { random, diagonal, rank1_radial, rank1_across };

// A covariance scaled as a frustum's at distance r would be (std 5% of r, at most 1e17 so it fits float32).
void contract_add_row(ContractBatch& b, std::mt19937& rng, std::array<double, 3> mean, CovKind kind) {
  std::normal_distribution<double> normal;
  const double r = std::max(1.0, std::hypot(mean[0], mean[1], mean[2]));
  const double scale = r < 1e15 ? (0.05 * r) * (0.05 * r) : 1e34;
  std::array<double, 3> u{1, 0, 0};
  if (std::hypot(mean[0], mean[1], mean[2]) > 0) {
    const double n = std::hypot(mean[0], mean[1], mean[2]);
    u = {mean[0] / n, mean[1] / n, mean[2] / n};
  }
  double m[3][3] = {};
  if (kind == CovKind::random) {
    double a[3][3];
    for (auto& row : a)
      for (double& x : row) x = normal(rng);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) m[i][j] += a[i][k] * a[j][k] * scale / 3;
  } else if (kind == CovKind::diagonal) {
    std::uniform_real_distribution<double> uni(0.1, 1.0);
    for (int i = 0; i < 3; ++i) m[i][i] = uni(rng) * scale;
  } else {
    std::array<double, 3> v = u;
    if (kind == CovKind::rank1_across) {  // u × (0.3, 0.5, 0.8), normalised
      v = {u[1] * 0.8 - u[2] * 0.5, u[2] * 0.3 - u[0] * 0.8, u[0] * 0.5 - u[1] * 0.3};
      const double n = std::hypot(v[0], v[1], v[2]);
      for (double& x : v) x /= n;
    }
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m[i][j] = v[i] * v[j] * scale;
  }
  for (int i = 0; i < 3; ++i) b.means.push_back(static_cast<float>(mean[i]));
  for (int i = 0; i < 3; ++i) b.covs.push_back(static_cast<float>(m[i][i]));
  for (auto [i, j] : {std::pair{0, 1}, std::pair{0, 2}, std::pair{1, 2}}) b.off.push_back(static_cast<float>(m[i][j]));
  ++b.rows;
}

std::array<double, 3> contract_random_direction(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  std::array<double, 3> v{normal(rng), normal(rng), normal(rng)};
  const double n = std::hypot(v[0], v[1], v[2]);
  return {v[0] / n, v[1] / n, v[2] / n};
}

// Inside, on the sphere, one float ulp either side, outside, far out (|x|² overflows float32 from 1.8e19), on the
// axes, at the origin; each with every kind of covariance.
ContractBatch contract_hard_batch(std::mt19937& rng) {
  ContractBatch b;
  const CovKind kinds[] = {CovKind::random, CovKind::diagonal, CovKind::rank1_radial, CovKind::rank1_across};
  auto add_at = [&](double radius) {
    const auto d = contract_random_direction(rng);
    for (CovKind kind : kinds) contract_add_row(b, rng, {d[0] * radius, d[1] * radius, d[2] * radius}, kind);
  };
  for (double radius : {0.3, 0.9, 1.0 - 0x1p-23, 1.0 + 0x1p-22, 1.5, 3.0, 20.0, 1e3, 1e6, 1e20, 1e30, 3e38}) {
    add_at(radius);
  }
  for (CovKind kind : kinds) {
    contract_add_row(b, rng, {1, 0, 0}, kind);  // exactly on the sphere: the inside branch
    contract_add_row(b, rng, {0, 0, 0}, kind);
    contract_add_row(b, rng, {0, -1e6, 0}, kind);
    contract_add_row(b, rng, {1e30, 0, 0}, kind);
  }
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (int i = 0; i < 24; ++i) add_at(test::log_uniform(rng, 0.05, 1e4));
  return b;
}

struct ContractRun {
  std::vector<float> means, covs, off;
};

ContractRun contract_run_fwd(const ContractBatch& b) {
  auto& ctx = test::test_context();
  ops::ContractGaussians stage(ctx);
  auto means = test::upload(ctx, b.means, "means"), covs = test::upload(ctx, b.covs, "covs"),
       off = test::upload(ctx, b.off, "cov_off");
  auto out_means = test::filled(ctx, 3 * b.rows, 7.0f, "out_means"),
       out_covs = test::filled(ctx, 3 * b.rows, 7.0f, "out_covs"),
       out_off = test::filled(ctx, 3 * b.rows, 7.0f, "out_cov_off");
  stage.fwd({means, covs, off, b.rows}, {out_means, out_covs, out_off});
  return {out_means.download(ctx), out_covs.download(ctx), out_off.download(ctx)};
}

ContractRun contract_run_bwd(const ContractBatch& b, const ContractBatch& d_out) {
  auto& ctx = test::test_context();
  ops::ContractGaussians stage(ctx);
  auto means = test::upload(ctx, b.means, "means"), covs = test::upload(ctx, b.covs, "covs"),
       off = test::upload(ctx, b.off, "cov_off");
  auto g_means = test::upload(ctx, d_out.means, "d_out_means"), g_covs = test::upload(ctx, d_out.covs, "d_out_covs"),
       g_off = test::upload(ctx, d_out.off, "d_out_cov_off");
  auto d_means = test::filled(ctx, 3 * b.rows, 7.0f, "d_means"), d_covs = test::filled(ctx, 3 * b.rows, 7.0f, "d_covs"),
       d_off = test::filled(ctx, 3 * b.rows, 7.0f, "d_cov_off");
  stage.bwd({means, covs, off, b.rows}, {g_means, g_covs, g_off, b.rows}, {d_means, d_covs, d_off});
  return {d_means.download(ctx), d_covs.download(ctx), d_off.download(ctx)};
}

struct ContractRef {
  std::vector<double> means, covs, off;
};

ContractRef contract_ref_fwd(const ContractBatch& b, double radius_scale = 1.0) {
  auto means = test::to_double(b.means);
  for (double& x : means) x *= radius_scale;
  ContractRef r;
  ref::contract_gaussians_fwd(means, test::to_double(b.covs), test::to_double(b.off), r.means, r.covs, r.off, b.rows);
  return r;
}

ContractRef contract_ref_bwd(const ContractBatch& b, const ContractBatch& d_out, double radius_scale = 1.0) {
  auto means = test::to_double(b.means);
  for (double& x : means) x *= radius_scale;
  ContractRef r;
  ref::contract_gaussians_bwd(means, test::to_double(b.covs), test::to_double(b.off), test::to_double(d_out.means),
                              test::to_double(d_out.covs), test::to_double(d_out.off), r.means, r.covs, r.off, b.rows);
  return r;
}

// Upstream gradients of order 1 for every output.
ContractBatch contract_upstream(const ContractBatch& b, std::mt19937& rng) {
  std::normal_distribution<float> normal;
  ContractBatch d = b;
  for (auto* v : {&d.means, &d.covs, &d.off})
    for (float& x : *v) x = normal(rng);
  return d;
}

// The independent oracle: J = ∂contract/∂x as the explicit matrix a δ_ij + (b − a) u_i u_j in long double, and
// J Σ Jᵀ by matrix products. Its a + (b − a) cancellation costs log2(2r) of long double's 64 bits: fine to r ~ 1e4.
void contract_oracle(const double x[3], const double diag[3], const double off[3], long double mean[3],
                     long double cov[3][3]) {
  const long double sigma[3][3] = {{diag[0], off[0], off[1]}, {off[0], diag[1], off[2]}, {off[1], off[2], diag[2]}};
  const long double r2 = (long double)x[0] * x[0] + (long double)x[1] * x[1] + (long double)x[2] * x[2];
  long double jac[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int i = 0; i < 3; ++i) mean[i] = x[i];
  if (r2 > 1) {
    const long double r = std::sqrt(r2), a = (2 * r - 1) / r2, b = 1 / r2;
    for (int i = 0; i < 3; ++i) {
      mean[i] = (2 - 1 / r) * x[i] / r;
      for (int j = 0; j < 3; ++j) jac[i][j] = (i == j ? a : 0) + (b - a) * (x[i] / r) * (x[j] / r);
    }
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      long double sum = 0;
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) sum += jac[i][k] * sigma[k][l] * jac[j][l];
      cov[i][j] = sum;
    }
}

double contract_entry_sum(const float* diag, const float* off) {
  double n = 0;
  for (int i = 0; i < 3; ++i) n += std::abs(diag[i]) + 2.0 * std::abs(off[i]);
  return n;
}

}  // namespace

TEST_CASE("contract gaussians: the reference against the explicit Jacobian product") {
  std::mt19937 rng(451);
  ContractBatch b;
  const CovKind kinds[] = {CovKind::random, CovKind::diagonal, CovKind::rank1_radial, CovKind::rank1_across};
  for (int i = 0; i < 200; ++i) {
    const auto d = contract_random_direction(rng);
    const double radius = test::log_uniform(rng, 0.05, 1e4);
    contract_add_row(b, rng, {d[0] * radius, d[1] * radius, d[2] * radius}, kinds[i % 4]);
  }
  const ContractRef r = contract_ref_fwd(b);
  double worst = 0;
  for (size_t row = 0; row < b.rows; ++row) {
    const double x[3] = {b.means[3 * row], b.means[3 * row + 1], b.means[3 * row + 2]};
    const double diag[3] = {b.covs[3 * row], b.covs[3 * row + 1], b.covs[3 * row + 2]};
    const double off[3] = {b.off[3 * row], b.off[3 * row + 1], b.off[3 * row + 2]};
    long double mean[3], cov[3][3];
    contract_oracle(x, diag, off, mean, cov);
    const double rr = std::max(1.0, std::hypot(x[0], x[1], x[2]));
    const double a = (2 * rr - 1) / (rr * rr), bb = 1 / (rr * rr);
    // Double rounding of a few dozen operations on terms ≤ 6 (a + b)² N (host/ref/contract.cpp), and the oracle's
    // cancellation: 1e-13 relative to that scale; the mean (≤ 2) to 1e-14 (about ten roundings of values ≤ 2).
    const double scale = (a + bb) * (a + bb) * contract_entry_sum(&b.covs[3 * row], &b.off[3 * row]);
    for (int i = 0; i < 3; ++i) {
      CHECK(std::abs(r.means[3 * row + i] - (double)mean[i]) <= 1e-14);
      const double e_diag = std::abs(r.covs[3 * row + i] - (double)cov[i][i]);
      const int j = i == 2 ? 1 : 0, k = i == 0 ? 1 : 2;  // off index i ↔ (j, k): 0 ↔ (0,1), 1 ↔ (0,2), 2 ↔ (1,2)
      const double e_off = std::abs(r.off[3 * row + i] - (double)cov[j][k]);
      worst = std::max(worst, std::max(e_diag, e_off) / scale);
      CHECK(e_diag <= 1e-13 * scale);
      CHECK(e_off <= 1e-13 * scale);
    }
  }
  MESSAGE("reference vs explicit Jacobian: worst error " << worst << " of (a + b)^2 N");
}

TEST_CASE("contract gaussians: the Jacobian is continuous across the unit sphere, identity inside, radius 2 outside") {
  std::mt19937 rng(452);
  for (int trial = 0; trial < 20; ++trial) {
    const auto d = contract_random_direction(rng);
    ContractBatch b;
    contract_add_row(b, rng, d, CovKind::random);
    const double diag[3] = {b.covs[0], b.covs[1], b.covs[2]}, off[3] = {b.off[0], b.off[1], b.off[2]};
    for (double delta : {1e-6, 1e-9}) {
      // J(1 + δ) = I + O(δ): a = 1 − δ² + O(δ³), b = 1 − 2δ + O(δ²), so Σ' − Σ is at most ~4δ N and the mean moves
      // by (1 + δ − δ²…) − 1 ≤ δ.
      ref::Gaussian3 outside{}, inside{};
      for (int i = 0; i < 3; ++i) {
        outside.mean[i] = d[i] * (1 + delta);
        inside.mean[i] = d[i] * (1 - delta);
        outside.diag[i] = inside.diag[i] = diag[i];
        outside.off[i] = inside.off[i] = off[i];
      }
      const auto o = ref::contract_gaussian(outside), in = ref::contract_gaussian(inside);
      const double n = contract_entry_sum(b.covs.data(), b.off.data());
      for (int i = 0; i < 3; ++i) {
        CHECK(in.diag[i] == diag[i]);  // identity inside
        CHECK(in.off[i] == off[i]);
        CHECK(std::abs(o.diag[i] - in.diag[i]) <= 4.5 * delta * n);
        CHECK(std::abs(o.off[i] - in.off[i]) <= 4.5 * delta * n);
        CHECK(std::abs(o.mean[i] - in.mean[i]) <= 2.5 * delta);
      }
    }
  }
  // Far out the means approach the sphere of radius 2 (|contract(x)| = 2 − 1/|x|), never beyond it.
  for (double radius : {2.0, 1e3, 1e20, 3e38}) {
    const auto d = contract_random_direction(rng);
    ref::Gaussian3 g{};
    for (int i = 0; i < 3; ++i) g.mean[i] = d[i] * radius;
    const auto o = ref::contract_gaussian(g);
    const double norm = std::hypot(o.mean[0], o.mean[1], o.mean[2]);
    CHECK(std::abs(norm - (2 - 1 / radius)) <= 8 * std::numeric_limits<double>::epsilon());
  }
}

TEST_CASE("contract gaussians: forward kernel against the reference, hard cases") {
  std::mt19937 rng(453);
  const ContractBatch b = contract_hard_batch(rng);
  const ContractRun k = contract_run_fwd(b);
  const ContractRef r = contract_ref_fwd(b);
  const auto bound = ref::contract_gaussians_fwd_float32_bound(test::to_double(b.means), test::to_double(b.covs),
                                                               test::to_double(b.off), b.rows);
  // Inside the ball (the sphere included) the bound is 0: the kernel copies bit for bit.
  MIPNERF_CHECK_CLOSE("contracted means", k.means, r.means, [&](size_t i) { return bound.means[i]; });
  MIPNERF_CHECK_CLOSE("contracted covs", k.covs, r.covs, [&](size_t i) { return bound.covs[i]; });
  MIPNERF_CHECK_CLOSE("contracted cov_off", k.off, r.off, [&](size_t i) { return bound.cov_off[i]; });
  // The bounds can fail: the reference at |x|·(1 + 1e-3) is beyond them (a 0.1% error of the radius).
  const ContractRef moved = contract_ref_fwd(b, 1.001);
  const auto covs_cmp = test::compare(test::to_float(moved.covs), r.covs, [&](size_t i) { return bound.covs[i]; });
  CHECK(covs_cmp.worst_ratio > 10);
}

TEST_CASE("contract gaussians: backward kernel against the reference, hard cases") {
  std::mt19937 rng(454);
  const ContractBatch b = contract_hard_batch(rng);
  const ContractBatch d_out = contract_upstream(b, rng);
  const ContractRun k = contract_run_bwd(b, d_out);
  const ContractRef r = contract_ref_bwd(b, d_out);
  const auto bound = ref::contract_gaussians_bwd_float32_bound(
      test::to_double(b.means), test::to_double(b.covs), test::to_double(b.off), test::to_double(d_out.means),
      test::to_double(d_out.covs), test::to_double(d_out.off), b.rows);
  MIPNERF_CHECK_CLOSE("d_means", k.means, r.means, [&](size_t i) { return bound.means[i]; });
  MIPNERF_CHECK_CLOSE("d_covs", k.covs, r.covs, [&](size_t i) { return bound.covs[i]; });
  MIPNERF_CHECK_CLOSE("d_cov_off", k.off, r.off, [&](size_t i) { return bound.cov_off[i]; });
  const ContractRef moved = contract_ref_bwd(b, d_out, 1.001);
  const auto means_cmp = test::compare(test::to_float(moved.means), r.means, [&](size_t i) { return bound.means[i]; });
  CHECK(means_cmp.worst_ratio > 10);
}

namespace {
// Rows away from the sphere (the covariance's derivative w.r.t. the mean jumps there: b′ goes from 0 to −2), with
// covariances of order 1 so that the differences see every term.
ContractBatch contract_fd_batch(std::mt19937& rng) {
  ContractBatch b;
  const CovKind kinds[] = {CovKind::random, CovKind::diagonal, CovKind::rank1_radial, CovKind::rank1_across};
  int i = 0;
  for (double radius : {0.3, 0.8, 1.2, 1.7, 3.0, 6.0, 15.0, 40.0}) {
    const auto d = contract_random_direction(rng);
    contract_add_row(b, rng, {d[0] * radius, d[1] * radius, d[2] * radius}, kinds[i++ % 4]);
  }
  return b;
}

std::vector<double> contract_flatten(const ContractBatch& b) {
  std::vector<double> v;
  for (const auto* part : {&b.means, &b.covs, &b.off}) v.insert(v.end(), part->begin(), part->end());
  return v;
}

ContractBatch contract_unflatten(const std::vector<double>& v, size_t rows) {
  ContractBatch b;
  b.rows = rows;
  b.means.assign(v.begin(), v.begin() + 3 * rows);
  b.covs.assign(v.begin() + 3 * rows, v.begin() + 6 * rows);
  b.off.assign(v.begin() + 6 * rows, v.end());
  return b;
}
}  // namespace

TEST_CASE("contract gaussians: backward against finite differences, reference and kernel") {
  std::mt19937 rng(455);
  const ContractBatch b = contract_fd_batch(rng);
  const ContractBatch d_out = contract_upstream(b, rng);
  const std::vector<double> weights = contract_flatten(d_out);
  // The reference, in double: inputs taken as doubles, the objective Σ weights · outputs.
  std::vector<double> x = contract_flatten(b);
  auto ref_objective = [&](const std::vector<double>& values) {
    ContractRef out;
    const size_t n = b.rows;
    ref::contract_gaussians_fwd({values.begin(), values.begin() + 3 * n},
                                {values.begin() + 3 * n, values.begin() + 6 * n},
                                {values.begin() + 6 * n, values.end()}, out.means, out.covs, out.off, n);
    std::vector<double> outputs = out.means;
    outputs.insert(outputs.end(), out.covs.begin(), out.covs.end());
    outputs.insert(outputs.end(), out.off.begin(), out.off.end());
    return test::weighted_sum(weights, outputs);
  };
  ContractRef grad;
  ref::contract_gaussians_bwd(test::to_double(b.means), test::to_double(b.covs), test::to_double(b.off),
                              test::to_double(d_out.means), test::to_double(d_out.covs), test::to_double(d_out.off),
                              grad.means, grad.covs, grad.off, b.rows);
  std::vector<double> analytic = grad.means;
  analytic.insert(analytic.end(), grad.covs.begin(), grad.covs.end());
  analytic.insert(analytic.end(), grad.off.begin(), grad.off.end());
  // h = 1e-5 on inputs of order 0.1–40: the truncation error h²/6 · |third derivative| ≲ 1e-10 · O(1), double
  // rounding of the objective (~1e-15 · Σ|weights · outputs| / h ≈ 1e-9): 1e-7 holds both with room.
  const auto ref_check = test::central_differences(x, analytic, ref_objective, 1, 1e-5);
  INFO("reference: worst |fd − analytic| " << ref_check.worst << ", largest gradient " << ref_check.largest_gradient);
  CHECK(ref_check.worst <= 1e-7 * std::max(1.0, ref_check.largest_gradient));

  // The kernel: its backward against central differences of its own forward at h = 1e-2. The two differ from the
  // reference's at the same h by (a) the reference's own truncation (the double difference at that h, computed), (b)
  // the kernel backward's float32 bound, (c) the forward's float32 noise, Σ |weights| · bound / h.
  const ContractRun k = contract_run_bwd(b, d_out);
  std::vector<double> kernel_grad = test::to_double(k.means);
  for (const auto* part : {&k.covs, &k.off}) kernel_grad.insert(kernel_grad.end(), part->begin(), part->end());
  const double h = 1e-2;
  const auto bwd_bound = ref::contract_gaussians_bwd_float32_bound(
      test::to_double(b.means), test::to_double(b.covs), test::to_double(b.off), test::to_double(d_out.means),
      test::to_double(d_out.covs), test::to_double(d_out.off), b.rows);
  std::vector<double> grad_bound = bwd_bound.means;
  grad_bound.insert(grad_bound.end(), bwd_bound.covs.begin(), bwd_bound.covs.end());
  grad_bound.insert(grad_bound.end(), bwd_bound.cov_off.begin(), bwd_bound.cov_off.end());
  double worst_ratio = 0;
  for (size_t e = 0; e < x.size(); ++e) {
    auto kernel_objective = [&](double delta) {
      std::vector<double> moved = x;
      moved[e] += delta;
      const ContractBatch mb = contract_unflatten(moved, b.rows);
      const ContractRun out = contract_run_fwd(mb);
      const auto fb = ref::contract_gaussians_fwd_float32_bound(test::to_double(mb.means), test::to_double(mb.covs),
                                                                test::to_double(mb.off), b.rows);
      std::vector<double> outputs = test::to_double(out.means), bounds = fb.means;
      for (const auto* part : {&out.covs, &out.off}) outputs.insert(outputs.end(), part->begin(), part->end());
      bounds.insert(bounds.end(), fb.covs.begin(), fb.covs.end());
      bounds.insert(bounds.end(), fb.cov_off.begin(), fb.cov_off.end());
      double noise = 0;
      for (size_t i = 0; i < bounds.size(); ++i) noise += std::abs(weights[i]) * bounds[i];
      return std::pair{test::weighted_sum(weights, outputs), noise};
    };
    // The moved inputs are rounded to float: the step the kernel sees is the float difference.
    const float up_x = static_cast<float>(x[e] + h), down_x = static_cast<float>(x[e] - h);
    const double step = static_cast<double>(up_x) - static_cast<double>(down_x);
    const auto [up, up_noise] = kernel_objective(static_cast<double>(up_x) - x[e]);
    const auto [down, down_noise] = kernel_objective(static_cast<double>(down_x) - x[e]);
    std::vector<double> xe = x;
    xe[e] = up_x;
    const double ref_up = ref_objective(xe);
    xe[e] = down_x;
    const double ref_down = ref_objective(xe);
    const double ref_truncation = std::abs((ref_up - ref_down) / step - analytic[e]);
    const double tolerance = ref_truncation + grad_bound[e] + (up_noise + down_noise) / step + 1e-12;
    const double error = std::abs((up - down) / step - kernel_grad[e]);
    CAPTURE(e);
    CHECK(error <= tolerance);
    worst_ratio = std::max(worst_ratio, error / tolerance);
  }
  MESSAGE("kernel finite differences: worst error " << worst_ratio << " x tolerance");
}

TEST_CASE("ray warp: kernels against the reference, far = inf included, and the endpoints") {
  auto& ctx = test::test_context();
  const float inf = std::numeric_limits<float>::infinity();
  for (const auto& bounds : {std::pair{0.2f, 1e6f}, std::pair{0.2f, inf}, std::pair{1.0f, inf}, std::pair{2.0f, 6.0f},
                             std::pair{0.5f, 0.51f}}) {
    const float near = bounds.first, far = bounds.second;  // not a structured binding: clang's lambdas cannot take one
    CAPTURE(near);
    CAPTURE(far);
    ops::RayWarp warp(ctx, near, far);
    std::vector<float> t{near}, s{0.0f};
    const float top = std::isinf(far) ? 1e8f : far;
    for (int i = 1; i < 16; ++i) t.push_back(near * std::pow(top / near, i / 15.0f));
    t.push_back(far);
    for (int i = 1; i < 16; ++i) s.push_back(i / 16.0f);
    s.push_back(1.0f - 0x1p-24f);
    s.push_back(1.0f);
    auto t_dev = test::upload(ctx, t, "t"), s_dev = test::upload(ctx, s, "s");
    auto s_out = test::filled(ctx, t.size(), 7.0f, "s_out"), t_out = test::filled(ctx, s.size(), 7.0f, "t_out"),
         dt_ds = test::filled(ctx, s.size(), 7.0f, "dt_ds");
    warp.t_to_s(t_dev, s_out, t.size());
    warp.s_to_t(s_dev, t_out, dt_ds, s.size());
    const auto ks = s_out.download(ctx), kt = t_out.download(ctx), kd = dt_ds.download(ctx);
    std::vector<double> rs, rt, rd;
    ref::ray_warp_t_to_s(test::to_double(t), rs, near, far);
    ref::ray_warp_s_to_t(test::to_double(s), rt, rd, near, far);
    // The endpoints exactly: t = near → s = 0 and t = far → s = 1 (the same fraction over itself, or ∞'s limit).
    CHECK(ks.front() == 0.0f);
    CHECK(ks.back() == 1.0f);
    CHECK(rs.back() == 1.0);
    // s = 1 with far = ∞ is t = ∞ and dt/ds = ∞ (left out of the comparison below: ∞ − ∞).
    const size_t finite_s = std::isinf(far) ? s.size() - 1 : s.size();
    if (std::isinf(far)) {
      CHECK(std::isinf(kt.back()));
      CHECK(std::isinf(kd.back()));
      CHECK(std::isinf(rt.back()));
    }
    rt.resize(finite_s);
    rd.resize(finite_s);
    MIPNERF_CHECK_CLOSE("t_to_s", ks, rs,
                        [&](size_t i) { return ref::ray_warp_t_to_s_float32_relative_bound() * std::abs(rs[i]); });
    MIPNERF_CHECK_CLOSE("s_to_t", kt, rt,
                        [&](size_t i) { return ref::ray_warp_s_to_t_float32_relative_bound() * std::abs(rt[i]); });
    MIPNERF_CHECK_CLOSE("dt_ds", kd, rd, [&](size_t i) {
      return ref::ray_warp_dt_ds_float32_relative_bound(near, far) * std::abs(rd[i]);
    });
  }
}

TEST_CASE("ray warp: the reference is the official formula, inverts itself, and its derivative") {
  for (const auto& bounds :
       {std::pair{0.2, 1e6}, std::pair{0.2, std::numeric_limits<double>::infinity()}, std::pair{2.0, 6.0}}) {
    const double near = bounds.first, far = bounds.second;  // not a structured binding (clang, doctest's lambdas)
    CAPTURE(near);
    CAPTURE(far);
    const double inv_near = 1 / near, inv_far = 1 / far;
    for (double s : {0.0, 0.1, 0.37, 0.5, 0.8, 0.999}) {
      const double t = ref::ray_warp_s_to_t_of(s, inv_near, inv_far);
      // construct_ray_warps' t_to_s as the official writes it, (1/t − 1/near)/(1/far − 1/near): 1e-14 relative.
      const double official_s = (1 / t - inv_near) / (inv_far - inv_near);
      CHECK(std::abs(ref::ray_warp_t_to_s_of(t, near, far) - s) <= 1e-14 * std::max(s, 1e-2));
      CHECK(std::abs(official_s - s) <= 1e-12 * std::max(s, 1e-2));
      // dt/ds against a central difference with h = 1e-4 (1 − s): for far = ∞, t = near/(1 − s) and the truncation
      // h² t'''/6 is h²/(1 − s)² = 1e-8 of t' (less for a finite far); rounding 1e-16 t / h is below 1e-10 of t'.
      const double h = 1e-4 * (1 - s);
      const double fd =
          (ref::ray_warp_s_to_t_of(s + h, inv_near, inv_far) - ref::ray_warp_s_to_t_of(s - h, inv_near, inv_far)) /
          (2 * h);
      const double analytic = ref::ray_warp_dt_ds_of(t, inv_near, inv_far);
      CHECK(std::abs(fd - analytic) <= 1e-6 * analytic);
    }
  }
}

TEST_CASE("ray warp: near = 0 and far <= near are refused with what to set") {
  auto& ctx = test::test_context();
  CHECK_THROWS_WITH_AS(ops::RayWarp(ctx, 0.0f, 6.0f), doctest::Contains("set a near bound > 0"), Error);
  CHECK_THROWS_WITH_AS(ops::RayWarp(ctx, -1.0f, 6.0f), doctest::Contains("near = -1"), Error);
  CHECK_THROWS_WITH_AS(ops::RayWarp(ctx, 2.0f, 2.0f), doctest::Contains("set far > near"), Error);
  CHECK_THROWS_WITH_AS(ops::RayWarp(ctx, 2.0f, std::nanf("")), doctest::Contains("set far > near"), Error);
  CHECK_NOTHROW(ops::RayWarp(ctx, 0.2f, std::numeric_limits<float>::infinity()));
}
