// CPU reference of kernels/contracted_ipe.cl.
#include "ref/contracted_ipe.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>

#include "ref/contract.hpp"
#include "ref/gaussian.hpp"

namespace mipnerf::ref {
namespace {

constexpr double kU = 5.9604644775390625e-08;  // float32's unit roundoff, 2^−24

struct Projected {
  double mean, var;
};

Projected project_row(const double* basis_k, const double* mean, const double* diag, const double* off) {
  const double* b = basis_k;
  return {b[0] * mean[0] + b[1] * mean[1] + b[2] * mean[2],
          b[0] * b[0] * diag[0] + b[1] * b[1] * diag[1] + b[2] * b[2] * diag[2] +
              2.0 * (b[0] * b[1] * off[0] + b[0] * b[2] * off[1] + b[1] * b[2] * off[2])};
}

// Σ_i |b_i|·x_i and Σ_ij |b_i b_j|·X_ij over the symmetric X = (diag, off): how entrywise bounds of a mean and a
// covariance become bounds of their projections onto b.
double project_mean_bound(const double* b, const double* x) {
  return std::abs(b[0]) * x[0] + std::abs(b[1]) * x[1] + std::abs(b[2]) * x[2];
}
double project_var_bound(const double* b, const double* diag, const double* off) {
  return b[0] * b[0] * diag[0] + b[1] * b[1] * diag[1] + b[2] * b[2] * diag[2] +
         2.0 * (std::abs(b[0] * b[1]) * off[0] + std::abs(b[0] * b[2]) * off[1] + std::abs(b[1] * b[2]) * off[2]);
}

}  // namespace

void contracted_gaussians(const GaussianOptions& options, const std::vector<double>& origins,
                          const std::vector<double>& directions, const std::vector<double>& radii,
                          const std::vector<double>& t_edges, std::vector<double>& means, std::vector<double>& covs,
                          std::vector<double>& cov_off, size_t n_rays, size_t n_samples) {
  std::vector<double> world_means, world_covs, world_off;
  gaussian_full_fwd(options, origins, directions, radii, t_edges, world_means, world_covs, world_off, n_rays,
                    n_samples);
  contract_gaussians_fwd(world_means, world_covs, world_off, means, covs, cov_off, n_rays * n_samples);
}

void project_gaussians(const std::vector<double>& means, const std::vector<double>& covs,
                       const std::vector<double>& cov_off, const std::vector<double>& basis,
                       std::vector<double>& lifted_means, std::vector<double>& lifted_vars, size_t n_rows) {
  const size_t k_count = basis.size() / 3;
  lifted_means.assign(n_rows * k_count, 0.0);
  lifted_vars.assign(n_rows * k_count, 0.0);
  for (size_t row = 0; row < n_rows; ++row) {
    for (size_t k = 0; k < k_count; ++k) {
      const Projected p = project_row(&basis[3 * k], &means[3 * row], &covs[3 * row], &cov_off[3 * row]);
      lifted_means[row * k_count + k] = p.mean;
      lifted_vars[row * k_count + k] = p.var;
    }
  }
}

void projected_ipe(const EncodingOptions& options, const std::vector<double>& lifted_means,
                   const std::vector<double>& lifted_vars, std::vector<double>& features, size_t n_rows,
                   size_t n_basis) {
  const size_t degrees = static_cast<size_t>(options.degrees()), block = degrees * n_basis;
  features.assign(n_rows * 2 * block, 0.0);
  for (size_t row = 0; row < n_rows; ++row) {
    double* sines = &features[row * 2 * block];
    double* cosines = sines + block;
    for (size_t l = 0; l < degrees; ++l) {
      const double scale = std::ldexp(1.0, options.min_deg + static_cast<int>(l));
      for (size_t k = 0; k < n_basis; ++k) {
        const double y = scale * lifted_means[row * n_basis + k];
        const double attenuation = std::exp(-0.5 * scale * scale * lifted_vars[row * n_basis + k]);
        sines[l * n_basis + k] = attenuation * std::sin(y);
        cosines[l * n_basis + k] = attenuation * std::cos(y);
      }
    }
  }
}

void contracted_ipe_fwd(const GaussianOptions& options, const EncodingOptions& encoding,
                        const std::vector<double>& origins, const std::vector<double>& directions,
                        const std::vector<double>& radii, const std::vector<double>& t_edges,
                        const std::vector<double>& basis, std::vector<double>& features, size_t n_rays,
                        size_t n_samples) {
  std::vector<double> means, covs, cov_off, lifted_means, lifted_vars;
  contracted_gaussians(options, origins, directions, radii, t_edges, means, covs, cov_off, n_rays, n_samples);
  project_gaussians(means, covs, cov_off, basis, lifted_means, lifted_vars, n_rays * n_samples);
  projected_ipe(encoding, lifted_means, lifted_vars, features, n_rays * n_samples, basis.size() / 3);
}

// The bound, stage by stage (u = 2^−24; each stage's rounding, then what it does to the errors before it):
//  1. The world Gaussian (gaussian.cl, float inputs): the moments t_mean, t_var, r_var are within 16u relative for
//     t0 ≥ 0 (gaussian.cl: no cancellation); μ_i = o_i + t_mean·d_i is then within 18u·(|o_i| + |t_mean·d_i|); every
//     covariance entry is a sum or difference of t_var·d_i·d_j and r_var·(…)/|d|² terms, each within 20u, so within
//     24u·S, S = t_var·|d|² + r_var (which bounds every term).
//  2. The contraction: its Jacobian's norm is ‖J‖ = max(a, b) = a = (2r − 1)/r² outside the ball (1 inside), which
//     decreases with r, so within |Δμ| of μ it is at most a(r − |Δμ|) (1 if that reaches the ball): the mean's error
//     passes scaled by that, plus the kernel's own rounding (ref::contract_gaussians_fwd_float32_bound). Σ' = JΣJ
//     takes ΔΣ to at most ‖J‖²·‖ΔΣ‖_F ≤ ‖J‖²·3·24u·S per entry, and J's change with the mean (|∂a/∂r|, |∂b/∂r| ≤
//     2/r², dP ~ 2/r) moves Σ' by at most 2·(4/r)·|Δμ'|/r·‖Σ‖_F with r = max(1, |μ|); plus the kernel's rounding.
//  3. The projection onto b (the basis' float values, exact inputs): Δm ≤ Σ|b_i|Δμ'_i + 3u·Σ|b_i μ'_i|, and
//     Δv ≤ Σ|b_i b_j|ΔΣ'_ij + 6u·Σ|b_i b_j Σ'_ij| (9 products, 8 additions, the factor 2).
//  4. The encoding: y = 2^l·m is exact, so sin(y) moves by ≤ 2^l·Δm; the attenuation A = exp(−½4^l v) of a v within
//     Δv (and the exponent's 2u) lies below A_hi = exp(−½4^l·max(0, v − Δv − 2u|v|)), so it moves by ≤ A_hi − A
//     + 4u·A_hi (exp's 4 ulp); sincos's 4 ulp and the product add 6u·A_hi; j angle doublings after a sincos (a sincos
//     every K degrees, j = l mod K) add (2^j·8 + (2^j − 1)·3)u·A_hi (encode.cl's bound of DOUBLE_ANGLE); a cut
//     attenuation (below exp(−87)) and the underflow of a product add 16·FLT_MIN.
std::vector<double> contracted_ipe_fwd_float32_bound(const GaussianOptions& options, const EncodingOptions& encoding,
                                                     int sincos_every,
                                                     const std::vector<double>& origins,
                                                     const std::vector<double>& directions,
                                                     const std::vector<double>& radii,
                                                     const std::vector<double>& t_edges,
                                                     const std::vector<double>& basis, size_t n_rays,
                                                     size_t n_samples) {
  const size_t n_rows = n_rays * n_samples, k_count = basis.size() / 3;
  std::vector<double> world_means, world_covs, world_off, means, covs, cov_off;
  gaussian_full_fwd(options, origins, directions, radii, t_edges, world_means, world_covs, world_off, n_rays,
                    n_samples);
  contract_gaussians_fwd(world_means, world_covs, world_off, means, covs, cov_off, n_rows);
  const ContractBounds own = contract_gaussians_fwd_float32_bound(world_means, world_covs, world_off, n_rows);
  const size_t degrees = static_cast<size_t>(encoding.degrees()), block = degrees * k_count;
  std::vector<double> bound(n_rows * 2 * block, 0.0);
  for (size_t row = 0; row < n_rows; ++row) {
    const size_t ray = row / n_samples, i = row % n_samples;
    const double* o = &origins[3 * ray];
    const double* d = &directions[3 * ray];
    const double t0 = t_edges[ray * (n_samples + 1) + i], t1 = t_edges[ray * (n_samples + 1) + i + 1];
    const auto m = options.ray_shape == RayShape::cylinder ? cylinder_moments(t0, t1, radii[ray])
                                                          : conical_frustum_moments(t0, t1, radii[ray]);
    const double d_sq = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    const double s_world = std::abs(m.t_var) * d_sq + std::abs(m.r_var);
    const double* mu = &world_means[3 * row];
    const double r = std::max(1.0, std::hypot(mu[0], mu[1], mu[2]));
    double mean_err = 0;  // |Δμ| (Euclidean, bounded by the sum of the components')
    for (int a = 0; a < 3; ++a) mean_err += 18.0 * kU * (std::abs(o[a]) + std::abs(m.t_mean * d[a]));
    double sigma_norm = 0;  // ‖Σ‖_F ≤ the sum of |entries|
    for (int a = 0; a < 3; ++a) sigma_norm += std::abs(world_covs[3 * row + a]) + 2 * std::abs(world_off[3 * row + a]);
    // ‖J‖ = max(a, b) = a = (2r − 1)/r² outside, decreasing in r: its value at r − |Δμ| bounds it near μ.
    const double r_low = r - mean_err;
    const double j_norm = r_low > 1.0 ? (2.0 * r_low - 1.0) / (r_low * r_low) : 1.0;
    mean_err *= j_norm;
    const double cov_propagated = 3.0 * 24.0 * kU * s_world * j_norm * j_norm + 8.0 / (r * r) * mean_err * sigma_norm;
    double mean_abs[3], mean_bound[3], diag_abs[3], off_abs[3], diag_bound[3], off_bound[3];
    for (int a = 0; a < 3; ++a) {
      mean_abs[a] = std::abs(means[3 * row + a]);
      mean_bound[a] = mean_err + own.means[3 * row + a];
      diag_abs[a] = std::abs(covs[3 * row + a]);
      off_abs[a] = std::abs(cov_off[3 * row + a]);
      diag_bound[a] = cov_propagated + own.covs[3 * row + a];
      off_bound[a] = cov_propagated + own.cov_off[3 * row + a];
    }
    for (size_t k = 0; k < k_count; ++k) {
      const double* b = &basis[3 * k];
      const Projected p = project_row(b, &means[3 * row], &covs[3 * row], &cov_off[3 * row]);
      const double dm = project_mean_bound(b, mean_bound) + 3.0 * kU * project_mean_bound(b, mean_abs);
      const double dv = project_var_bound(b, diag_bound, off_bound) + 6.0 * kU * project_var_bound(b, diag_abs, off_abs);
      for (size_t l = 0; l < degrees; ++l) {
        const double scale = std::ldexp(1.0, encoding.min_deg + static_cast<int>(l));
        const double attenuation = std::exp(-0.5 * scale * scale * p.var);
        const double a_hi = std::exp(-0.5 * scale * scale * std::max(0.0, p.var - dv - 2.0 * kU * std::abs(p.var)));
        const double doublings = std::ldexp(1.0, static_cast<int>(l) % std::max(1, sincos_every));
        const double angle = (doublings * 8.0 + (doublings - 1.0) * 3.0) * kU;
        const double e = std::min(2.0, scale * dm) * a_hi + (a_hi - attenuation) + (10.0 * kU + angle) * a_hi +
                         16.0 * FLT_MIN;
        bound[row * 2 * block + l * k_count + k] = e;
        bound[row * 2 * block + block + l * k_count + k] = e;
      }
    }
  }
  return bound;
}

}  // namespace mipnerf::ref
