// CPU reference (double) of kernels/contract.cl, same names: mip-NeRF 360's contraction of Gaussians (eq. 10 and the
// official coord.track_linearize: μ' = contract(μ), Σ' = J Σ Jᵀ, in the kernel's split of J into a tangential scale
// a = (2r − 1)/r² and a radial one b = 1/r²), its backward, and the ray warps of coord.construct_ray_warps with
// fn = reciprocal. Also the float32 error bounds of the kernels for the tests (derived beside each).
//
// Covariances are symmetric 3x3: diag (xx, yy, zz) and off (xy, xz, yz), each [rows][3], as the Gaussian stage's
// covariance_off_diagonal; off is one stored number for the two entries Σ_ij = Σ_ji, and its gradient is the
// derivative w.r.t. that number (the sum of the two entries' gradients).
#pragma once

#include <cstddef>
#include <vector>

namespace mipnerf::ref {

// One Gaussian's mean and symmetric covariance.
struct Gaussian3 {
  double mean[3];
  double diag[3];
  double off[3];  // xy, xz, yz
};

// Outside the unit ball iff |x|² > 1 (the official's where(x_mag_sq <= 1, x, ...)).
bool contract_is_outside(const double x[3]);

// u = x/|x| and 1/|x| by the kernel's exact power-of-two scaling (|x|² is never formed).
void contract_direction(const double x[3], double u[3], double* inv_r);

// Mirror of contract_jacobian_sandwich: J X J for the symmetric X = (diag, off) at a point outside the ball.
void contract_jacobian_sandwich(const double u[3], double inv_r, const double diag[3], const double off[3],
                                double out_diag[3], double out_off[3]);

// One Gaussian through the contraction (the kernel's per-row body).
Gaussian3 contract_gaussian(const Gaussian3& in);

// One Gaussian's backward: the gradients w.r.t. (mean, diag, off) given those w.r.t. the outputs (`d_out`).
Gaussian3 contract_gaussian_bwd(const Gaussian3& in, const Gaussian3& d_out);

// Mirrors contract_gaussians_fwd: means, covs, cov_off [rows][3] → out_means, out_covs, out_cov_off [rows][3].
void contract_gaussians_fwd(const std::vector<double>& means, const std::vector<double>& covs,
                            const std::vector<double>& cov_off, std::vector<double>& out_means,
                            std::vector<double>& out_covs, std::vector<double>& out_cov_off, size_t n_rows);

// Mirrors contract_gaussians_bwd: d_means, d_covs, d_cov_off [rows][3] from the outputs' gradients [rows][3].
void contract_gaussians_bwd(const std::vector<double>& means, const std::vector<double>& covs,
                            const std::vector<double>& cov_off, const std::vector<double>& d_out_means,
                            const std::vector<double>& d_out_covs, const std::vector<double>& d_out_cov_off,
                            std::vector<double>& d_means, std::vector<double>& d_covs, std::vector<double>& d_cov_off,
                            size_t n_rows);

// The float32 kernels' error bounds per output element, [rows][3] each (see contract.cpp for the derivation): zero
// inside the ball (the kernels copy), a few hundred roundings of the terms' magnitudes outside, plus an absolute
// 16·FLT_MIN for results that underflow.
struct ContractBounds {
  std::vector<double> means, covs, cov_off;
};
ContractBounds contract_gaussians_fwd_float32_bound(const std::vector<double>& means, const std::vector<double>& covs,
                                                    const std::vector<double>& cov_off, size_t n_rows);
ContractBounds contract_gaussians_bwd_float32_bound(const std::vector<double>& means, const std::vector<double>& covs,
                                                    const std::vector<double>& cov_off,
                                                    const std::vector<double>& d_out_means,
                                                    const std::vector<double>& d_out_covs,
                                                    const std::vector<double>& d_out_cov_off, size_t n_rows);

// The ray warps (construct_ray_warps, fn = reciprocal), near > 0, far > near or +∞:
//   t_to_s(t) = (1/t − 1/near)/(1/far − 1/near),  s_to_t(s) = 1/(s/far + (1 − s)/near),  dt/ds = t² (1/near − 1/far).
double ray_warp_t_to_s_of(double t, double near, double far);
double ray_warp_s_to_t_of(double s, double inv_near, double inv_far);
double ray_warp_dt_ds_of(double t, double inv_near, double inv_far);

// Mirrors ray_warp_t_to_s: s [n] from t [n].
void ray_warp_t_to_s(const std::vector<double>& t, std::vector<double>& s, double near, double far);
// Mirrors ray_warp_s_to_t: t [n] and dt_ds [n] from s [n].
void ray_warp_s_to_t(const std::vector<double>& s, std::vector<double>& t, std::vector<double>& dt_ds, double near,
                     double far);

// The kernels' float32 bounds, relative: |s − s_ref| ≤ this · |s_ref| (and likewise for t, dt_ds).
double ray_warp_t_to_s_float32_relative_bound();
double ray_warp_s_to_t_float32_relative_bound();
double ray_warp_dt_ds_float32_relative_bound(double near, double far);

}  // namespace mipnerf::ref
