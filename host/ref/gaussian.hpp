// CPU reference of kernels/gaussian.cl: frustum/cylinder moments (templated on the real type, so tests can
// evaluate them in long double) and the lifted 3-D Gaussians in double.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

#include "core/stage_options.hpp"

namespace mipnerf::ref {

// Moments of one interval along a ray: mean and variance of t, and the variance of each perpendicular axis.
template <typename T>
struct FrustumMoments {
  T t_mean, t_var, r_var;
};

// Conical frustum, supplement eq. 23 (the stable form; official conical_frustum_to_gaussian, stable=True), with
// t_μ = (t0 + t1)/2 and t_δ = (t1 − t0)/2, evaluated as in the kernel (ratio = t_δ²/(3t_μ² + t_δ²) ≤ 1, q =
// (12t_μ² − t_δ²)/(3t_μ² + t_δ²)) so that it matches rearrangement for rearrangement.
template <typename T>
FrustumMoments<T> conical_frustum_moments(T t0, T t1, T radius) {
  const T mu = (t0 + t1) / 2, hw = (t1 - t0) / 2;
  const T mu2 = mu * mu, hw2 = hw * hw;
  const T denom = 3 * mu2 + hw2;
  if (denom == 0) return {T(0), T(0), T(0)};  // t0 = t1 = 0: every numerator is 0 too
  const T ratio = hw2 / denom, q = (12 * mu2 - hw2) / denom;
  return {mu * (1 + 2 * ratio), hw2 * (T(1) / 3 - T(4) / 15 * ratio * q),
          radius * radius * (mu2 / 4 + hw2 * (T(5) / 12 - T(4) / 15 * ratio))};
}

// Conical frustum, supplement eqs. 20–22 as written (official stable=False): differences of powers of t0 and t1,
// which cancel catastrophically for thin frustums. Kept to show that failure in the tests.
template <typename T>
FrustumMoments<T> conical_frustum_moments_naive(T t0, T t1, T radius) {
  const T t0_3 = t0 * t0 * t0, t1_3 = t1 * t1 * t1;
  const T t0_4 = t0_3 * t0, t1_4 = t1_3 * t1, t0_5 = t0_4 * t0, t1_5 = t1_4 * t1;
  const T t_mean = (3 * (t1_4 - t0_4)) / (4 * (t1_3 - t0_3));
  const T t_mean_sq = T(3) / 5 * (t1_5 - t0_5) / (t1_3 - t0_3);
  return {t_mean, t_mean_sq - t_mean * t_mean, radius * radius * (T(3) / 20 * (t1_5 - t0_5) / (t1_3 - t0_3))};
}

// Cylinder of radius r (official cylinder_to_gaussian): t uniform on [t0, t1], a uniform disc across.
template <typename T>
FrustumMoments<T> cylinder_moments(T t0, T t1, T radius) {
  return {(t0 + t1) / 2, (t1 - t0) * (t1 - t0) / 12, radius * radius / 4};
}

// Official lift_gaussian (diag): mean = o + t_mean·d, cov = t_var·d² + r_var·(1 − d²/max(1e-10, |d|²)), with
// 1 − d_a²/|d|² written as the kernel writes it, (sum of the other two squares)/max(1e-10, |d|²): equal wherever
// |d|² ≥ 1e-10, and like the kernel a zero direction gets a zero covariance (the official form gives r_var there).
template <typename T>
void lift_gaussian(const T o[3], const T d[3], const FrustumMoments<T>& m, T mean[3], T cov[3]) {
  const T squares[3] = {d[0] * d[0], d[1] * d[1], d[2] * d[2]};
  const T d_mag_sq = std::max(T(1e-10), squares[0] + squares[1] + squares[2]);
  for (int a = 0; a < 3; ++a) {
    mean[a] = o[a] + m.t_mean * d[a];
    const T others = squares[(a + 1) % 3] + squares[(a + 2) % 3];
    cov[a] = m.t_var * squares[a] + m.r_var * (others / d_mag_sq);
  }
}

// Mirror of covariance_off_diagonal: (Σ_xy, Σ_xz, Σ_yz) of the full covariance (official lift_gaussian, diag = False),
// Σ_ij = (t_var − r_var/max(1e-10, |d|²))·d_i·d_j for i ≠ j.
template <typename T>
void covariance_off_diagonal(const T d[3], const FrustumMoments<T>& m, T off[3]) {
  const T d_mag_sq = std::max(T(1e-10), d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  const T along_minus_across = m.t_var - m.r_var / d_mag_sq;
  off[0] = along_minus_across * d[0] * d[1];
  off[1] = along_minus_across * d[0] * d[2];
  off[2] = along_minus_across * d[1] * d[2];
}

// Mirror of gaussian_fwd (mip-NeRF §3.1: supplement eq. 23 or the cylinder, lifted to 3-D): means, covs [R][N][3] from
// origins, directions [R][3], radii [R], t_edges [R][N+1].
void gaussian_fwd(const GaussianOptions& options, const std::vector<double>& origins,
                  const std::vector<double>& directions, const std::vector<double>& radii,
                  const std::vector<double>& t_edges, std::vector<double>& means, std::vector<double>& covs,
                  size_t n_rays, size_t n_samples);

// The full Gaussians the concatenated-PE kernel computes inline: means, covs (diagonal) as gaussian_fwd, and
// cov_off [R][N][3] = (Σ_xy, Σ_xz, Σ_yz).
void gaussian_full_fwd(const GaussianOptions& options, const std::vector<double>& origins,
                       const std::vector<double>& directions, const std::vector<double>& radii,
                       const std::vector<double>& t_edges, std::vector<double>& means, std::vector<double>& covs,
                       std::vector<double>& cov_off, size_t n_rays, size_t n_samples);

// Mirror of gaussian_points_fwd (NeRF's point samples): means = o + t_mid·d, covs = 0.
void gaussian_points_fwd(const std::vector<double>& origins, const std::vector<double>& directions,
                         const std::vector<double>& t_edges, std::vector<double>& means, std::vector<double>& covs,
                         size_t n_rays, size_t n_samples);

}  // namespace mipnerf::ref
