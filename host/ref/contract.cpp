// CPU reference (double) of kernels/contract.cl, and the float32 error bounds of its kernels.
#include "ref/contract.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>

namespace mipnerf::ref {

namespace {

// Unit roundoff of float32; OpenCL allows 2.5 ulp (5 u) for a float division and 2 ulp (4 u) for rsqrt, and rounds
// +, −, × correctly (1 u).
constexpr double kContractU = 5.9604644775390625e-08;
// Results that underflow: each scale factor is applied to a value that stays normal until the result is below
// FLT_MIN, so a flushed or denormal result is off by at most a few FLT_MIN.
constexpr double kContractUnderflow = 16.0 * FLT_MIN;

double contract_dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

void contract_sym_times(const double diag[3], const double off[3], const double v[3], double out[3]) {
  out[0] = diag[0] * v[0] + off[0] * v[1] + off[1] * v[2];
  out[1] = off[0] * v[0] + diag[1] * v[1] + off[2] * v[2];
  out[2] = off[1] * v[0] + off[2] * v[1] + diag[2] * v[2];
}

void contract_sym_pair_off(const double p[3], const double q[3], double out[3]) {
  out[0] = p[0] * q[1] + q[0] * p[1];
  out[1] = p[0] * q[2] + q[0] * p[2];
  out[2] = p[1] * q[2] + q[1] * p[2];
}

// Mirror of the kernel's ContractSplit.
struct ContractSplitRef {
  double perp_diag[3], perp_off[3], cross_diag[3], cross_off[3], radial_diag[3], radial_off[3];
  double v[3], w[3];
  double s;
};

ContractSplitRef contract_split(const double u[3], const double diag[3], const double off[3]) {
  ContractSplitRef p{};
  contract_sym_times(diag, off, u, p.v);
  p.s = contract_dot(u, p.v);
  for (int i = 0; i < 3; ++i) p.w[i] = p.v[i] - p.s * u[i];
  for (int i = 0; i < 3; ++i) p.cross_diag[i] = 2.0 * u[i] * p.w[i];
  contract_sym_pair_off(u, p.w, p.cross_off);
  const double uu_off[3] = {u[0] * u[1], u[0] * u[2], u[1] * u[2]};
  for (int i = 0; i < 3; ++i) {
    p.radial_diag[i] = p.s * (u[i] * u[i]);
    p.radial_off[i] = p.s * uu_off[i];
    p.perp_diag[i] = diag[i] - p.cross_diag[i] - p.radial_diag[i];
    p.perp_off[i] = off[i] - p.cross_off[i] - p.radial_off[i];
  }
  return p;
}

// Σ_ij |X_ij| over the 9 entries of the symmetric X = (diag, off).
double contract_entry_sum(const double diag[3], const double off[3]) {
  return std::abs(diag[0]) + std::abs(diag[1]) + std::abs(diag[2]) +
         2.0 * (std::abs(off[0]) + std::abs(off[1]) + std::abs(off[2]));
}

// (a, b, 1/r) at x, exactly (for the bounds): a = (2r − 1)/r², b = 1/r²; (1, 1, 1) inside.
struct ContractScales {
  double a, b, inv_r;
};
ContractScales contract_scales(const double x[3]) {
  if (!contract_is_outside(x)) return {1.0, 1.0, 1.0};
  const double r = std::hypot(x[0], x[1], x[2]);
  return {(2.0 * r - 1.0) / (r * r), 1.0 / (r * r), 1.0 / r};
}

}  // namespace

bool contract_is_outside(const double x[3]) {
  if (std::max({std::abs(x[0]), std::abs(x[1]), std::abs(x[2])}) > 1.0) return true;
  return contract_dot(x, x) > 1.0;
}

void contract_direction(const double x[3], double u[3], double* inv_r) {
  const double biggest = std::max({std::abs(x[0]), std::abs(x[1]), std::abs(x[2])});
  const int k = std::ilogb(biggest);
  const double scaled[3] = {std::ldexp(x[0], -k), std::ldexp(x[1], -k), std::ldexp(x[2], -k)};
  const double inv_norm = 1.0 / std::sqrt(contract_dot(scaled, scaled));
  for (int i = 0; i < 3; ++i) u[i] = scaled[i] * inv_norm;
  *inv_r = std::ldexp(inv_norm, -k);
}

void contract_jacobian_sandwich(const double u[3], double inv_r, const double diag[3], const double off[3],
                                double out_diag[3], double out_off[3]) {
  const double a = (2.0 - inv_r) * inv_r;
  const ContractSplitRef p = contract_split(u, diag, off);
  for (int i = 0; i < 3; ++i) {
    out_diag[i] = (p.perp_diag[i] * a) * a + ((p.cross_diag[i] * a) * inv_r) * inv_r +
                  (((p.radial_diag[i] * inv_r) * inv_r) * inv_r) * inv_r;
    out_off[i] = (p.perp_off[i] * a) * a + ((p.cross_off[i] * a) * inv_r) * inv_r +
                 (((p.radial_off[i] * inv_r) * inv_r) * inv_r) * inv_r;
  }
}

Gaussian3 contract_gaussian(const Gaussian3& in) {
  if (!contract_is_outside(in.mean)) return in;
  Gaussian3 out{};
  double u[3], inv_r;
  contract_direction(in.mean, u, &inv_r);
  contract_jacobian_sandwich(u, inv_r, in.diag, in.off, out.diag, out.off);
  for (int i = 0; i < 3; ++i) out.mean[i] = (2.0 - inv_r) * u[i];
  return out;
}

// The kernel's contract_gaussians_bwd, derivation there.
Gaussian3 contract_gaussian_bwd(const Gaussian3& in, const Gaussian3& d_out) {
  if (!contract_is_outside(in.mean)) return d_out;
  Gaussian3 d{};
  const double g_off[3] = {0.5 * d_out.off[0], 0.5 * d_out.off[1], 0.5 * d_out.off[2]};
  double u[3], inv_r;
  contract_direction(in.mean, u, &inv_r);
  contract_jacobian_sandwich(u, inv_r, d_out.diag, g_off, d.diag, d.off);
  for (double& o : d.off) o *= 2.0;

  const double a = (2.0 - inv_r) * inv_r;
  const double a_slope_over_r2 = -2.0 * (1.0 - inv_r);
  const double* g = d_out.mean;
  const double g_along = contract_dot(u, g);
  const ContractSplitRef sigma = contract_split(u, in.diag, in.off);
  double p[3], sigma_p[3], k_u[3], kt_p[3], g_k_u[3];
  contract_sym_times(d_out.diag, g_off, u, p);
  const double p_u = contract_dot(p, u), p_w = contract_dot(p, sigma.w);
  for (int i = 0; i < 3; ++i) k_u[i] = sigma.w[i] * a + ((sigma.s * u[i]) * inv_r) * inv_r;
  contract_sym_times(in.diag, in.off, p, sigma_p);
  for (int i = 0; i < 3; ++i) kt_p[i] = (sigma_p[i] - p_u * sigma.v[i]) * a + ((p_u * sigma.v[i]) * inv_r) * inv_r;
  contract_sym_times(d_out.diag, g_off, k_u, g_k_u);
  const double h_uu = 2.0 * contract_dot(p, k_u);
  double tr_g_perp = 0.0;
  for (int i = 0; i < 3; ++i) tr_g_perp += d_out.diag[i] * sigma.perp_diag[i];
  double tr_g_perp_off = 0.0;
  for (int i = 0; i < 3; ++i) tr_g_perp_off += g_off[i] * sigma.perp_off[i];
  tr_g_perp += 2.0 * tr_g_perp_off;
  const double tr_perp_h = 2.0 * (tr_g_perp * a + (p_w * inv_r) * inv_r);
  const double radial = ((tr_perp_h * inv_r) * inv_r) * a_slope_over_r2 + (((h_uu * inv_r) * inv_r) * inv_r) * -2.0;
  for (int i = 0; i < 3; ++i) {
    const double h_u = g_k_u[i] + kt_p[i];
    const double tangential = (((h_u - h_uu * u[i]) * inv_r) * inv_r) * (2.0 * a_slope_over_r2);
    d.mean[i] = (g[i] - g_along * u[i]) * a + ((g_along * u[i]) * inv_r) * inv_r + (radial * u[i] + tangential);
  }
  return d;
}

namespace {
Gaussian3 contract_row(const std::vector<double>& means, const std::vector<double>& covs,
                       const std::vector<double>& cov_off, size_t row) {
  Gaussian3 g{};
  for (int i = 0; i < 3; ++i) {
    g.mean[i] = means[3 * row + i];
    g.diag[i] = covs[3 * row + i];
    g.off[i] = cov_off[3 * row + i];
  }
  return g;
}

void contract_store_row(const Gaussian3& g, std::vector<double>& means, std::vector<double>& covs,
                        std::vector<double>& cov_off, size_t row) {
  for (int i = 0; i < 3; ++i) {
    means[3 * row + i] = g.mean[i];
    covs[3 * row + i] = g.diag[i];
    cov_off[3 * row + i] = g.off[i];
  }
}
}  // namespace

void contract_gaussians_fwd(const std::vector<double>& means, const std::vector<double>& covs,
                            const std::vector<double>& cov_off, std::vector<double>& out_means,
                            std::vector<double>& out_covs, std::vector<double>& out_cov_off, size_t n_rows) {
  out_means.assign(3 * n_rows, 0.0);
  out_covs.assign(3 * n_rows, 0.0);
  out_cov_off.assign(3 * n_rows, 0.0);
  for (size_t row = 0; row < n_rows; ++row) {
    contract_store_row(contract_gaussian(contract_row(means, covs, cov_off, row)), out_means, out_covs, out_cov_off,
                       row);
  }
}

void contract_gaussians_bwd(const std::vector<double>& means, const std::vector<double>& covs,
                            const std::vector<double>& cov_off, const std::vector<double>& d_out_means,
                            const std::vector<double>& d_out_covs, const std::vector<double>& d_out_cov_off,
                            std::vector<double>& d_means, std::vector<double>& d_covs, std::vector<double>& d_cov_off,
                            size_t n_rows) {
  d_means.assign(3 * n_rows, 0.0);
  d_covs.assign(3 * n_rows, 0.0);
  d_cov_off.assign(3 * n_rows, 0.0);
  for (size_t row = 0; row < n_rows; ++row) {
    const Gaussian3 d = contract_gaussian_bwd(contract_row(means, covs, cov_off, row),
                                              contract_row(d_out_means, d_out_covs, d_out_cov_off, row));
    contract_store_row(d, d_means, d_covs, d_cov_off, row);
  }
}

// Bounds of the float32 kernels, by first-order error analysis of the expressions as the kernel writes them
// (FP_CONTRACT off). The factors and their relative errors: the squares' sum q of the scaled x ≤ 3 u, rsqrt(q)
// ≤ 1.5 u + 4 u, so u_i ≤ 6.5 u and inv_r ≤ 5.5 u (the power-of-two scalings are exact); α = 2 − inv_r ≤ 6.5 u,
// a = α·inv_r ≤ 13 u.
//  - mean' = α u_i: ≤ 14 u relative → 16 u |mean'_i|.
//  - J X J: every entry is a sum of terms, each one entry of X times at most four u components and two scale factors
//    (a·a, a·inv_r², or inv_r⁴: ≤ 26 u), with about 20 roundings along its way (v = Xu, s = u·v, w = v − s u, the
//    parts, the scalings, the final sums): ≤ 4·6.5 + 26 + 20 = 72 u per term. The terms' magnitudes add up to at most
//    (6a² + 4ab + b²)·N ≤ 6 (a + b)² N, N = Σ_ij |X_ij| over the nine entries (|v_j|, |s| ≤ N and |w_j| ≤ 2N), so
//    |error| ≤ 72·6 u (a + b)² N ≤ 480 u (a + b)² N.
//  - d_mean: J g's terms ≤ 2 (a + b) |g|₁ at ≤ 30 u each; the terms of J′ (a′ = −2(1 − inv_r)·inv_r², whose factor
//    1 − inv_r has an absolute error ≤ 6.5 u; |a′|, |b′| ≤ 2 inv_r²) add up to ≤ 80 inv_r² (a + b) N_G N_Σ, from
//    |Ku| ≤ (2a + b) N_Σ, |p| ≤ N_G, |Hu| ≤ 2 (2a + b) N_G N_Σ, |tr⊥(H)| ≤ 2 (6a + 2b) N_G N_Σ and
//    |uᵀHu| ≤ 2 (2a + b) N_G N_Σ; each term has ≤ 4 u components, a, five inv_r factors and ~12 roundings: ≤ 100 u.
// Every result that underflows is also off by up to kContractUnderflow. Inside the ball the kernels copy: bound 0.
ContractBounds contract_gaussians_fwd_float32_bound(const std::vector<double>& means, const std::vector<double>& covs,
                                                    const std::vector<double>& cov_off, size_t n_rows) {
  ContractBounds b{std::vector<double>(3 * n_rows, 0.0), std::vector<double>(3 * n_rows, 0.0),
                   std::vector<double>(3 * n_rows, 0.0)};
  for (size_t row = 0; row < n_rows; ++row) {
    const Gaussian3 g = contract_row(means, covs, cov_off, row);
    if (!contract_is_outside(g.mean)) continue;
    const ContractScales sc = contract_scales(g.mean);
    const Gaussian3 out = contract_gaussian(g);
    const double cov_bound = 480.0 * kContractU * (sc.a + sc.b) * (sc.a + sc.b) * contract_entry_sum(g.diag, g.off);
    for (int i = 0; i < 3; ++i) {
      b.means[3 * row + i] = 16.0 * kContractU * std::abs(out.mean[i]) + kContractUnderflow;
      b.covs[3 * row + i] = cov_bound + kContractUnderflow;
      b.cov_off[3 * row + i] = cov_bound + kContractUnderflow;
    }
  }
  return b;
}

ContractBounds contract_gaussians_bwd_float32_bound(const std::vector<double>& means, const std::vector<double>& covs,
                                                    const std::vector<double>& cov_off,
                                                    const std::vector<double>& d_out_means,
                                                    const std::vector<double>& d_out_covs,
                                                    const std::vector<double>& d_out_cov_off, size_t n_rows) {
  ContractBounds b{std::vector<double>(3 * n_rows, 0.0), std::vector<double>(3 * n_rows, 0.0),
                   std::vector<double>(3 * n_rows, 0.0)};
  for (size_t row = 0; row < n_rows; ++row) {
    const Gaussian3 g = contract_row(means, covs, cov_off, row);
    if (!contract_is_outside(g.mean)) continue;
    const Gaussian3 d = contract_row(d_out_means, d_out_covs, d_out_cov_off, row);
    const double g_off[3] = {0.5 * d.off[0], 0.5 * d.off[1], 0.5 * d.off[2]};
    const ContractScales sc = contract_scales(g.mean);
    const double n_g = contract_entry_sum(d.diag, g_off), n_sigma = contract_entry_sum(g.diag, g.off);
    const double g_sum = std::abs(d.mean[0]) + std::abs(d.mean[1]) + std::abs(d.mean[2]);
    const double cov_bound = 480.0 * kContractU * (sc.a + sc.b) * (sc.a + sc.b) * n_g;
    const double mean_bound =
        100.0 * kContractU * (2.0 * (sc.a + sc.b) * g_sum + 80.0 * sc.inv_r * sc.inv_r * (sc.a + sc.b) * n_g * n_sigma);
    for (int i = 0; i < 3; ++i) {
      b.means[3 * row + i] = mean_bound + kContractUnderflow;
      b.covs[3 * row + i] = cov_bound + kContractUnderflow;
      b.cov_off[3 * row + i] = 2.0 * cov_bound + kContractUnderflow;
    }
  }
  return b;
}

double ray_warp_t_to_s_of(double t, double near, double far) {
  const double along = std::isinf(t) ? 1.0 : (t - near) / t;
  const double span = std::isinf(far) ? 1.0 : (far - near) / far;
  return along / span;
}

double ray_warp_s_to_t_of(double s, double inv_near, double inv_far) {
  return 1.0 / (s * inv_far + (1.0 - s) * inv_near);
}

double ray_warp_dt_ds_of(double t, double inv_near, double inv_far) { return t * t * (inv_near - inv_far); }

void ray_warp_t_to_s(const std::vector<double>& t, std::vector<double>& s, double near, double far) {
  s.resize(t.size());
  for (size_t i = 0; i < t.size(); ++i) s[i] = ray_warp_t_to_s_of(t[i], near, far);
}

void ray_warp_s_to_t(const std::vector<double>& s, std::vector<double>& t, std::vector<double>& dt_ds, double near,
                     double far) {
  const double inv_near = 1.0 / near, inv_far = 1.0 / far;
  t.resize(s.size());
  dt_ds.resize(s.size());
  for (size_t i = 0; i < s.size(); ++i) {
    t[i] = ray_warp_s_to_t_of(s[i], inv_near, inv_far);
    dt_ds[i] = ray_warp_dt_ds_of(t[i], inv_near, inv_far);
  }
}

// t_to_s: t − near and far − near (1 u each), three divisions (5 u each): 17 u → 20 u.
double ray_warp_t_to_s_float32_relative_bound() { return 20.0 * kContractU; }
// s_to_t: 1/near, 1/far (5 u each), two products and 1 − s (1 u each), a sum of non-negative terms (1 u), the
// reciprocal (5 u): ≤ 13 u → 16 u.
double ray_warp_s_to_t_float32_relative_bound() { return 16.0 * kContractU; }
// dt/ds = t·t·(1/near − 1/far): t twice (2·13 u), two products (2 u), and the difference of the reciprocals, whose
// 5 u each is amplified by κ = (1/near + 1/far)/(1/near − 1/far) = (far + near)/(far − near) (1 for far = ∞), + 1 u.
double ray_warp_dt_ds_float32_relative_bound(double near, double far) {
  const double kappa = std::isinf(far) ? 1.0 : (far + near) / (far - near);
  return (30.0 + 5.0 * kappa) * kContractU;
}

}  // namespace mipnerf::ref
