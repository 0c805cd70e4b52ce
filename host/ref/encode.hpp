// CPU reference of kernels/encode.cl: integrated and plain positional encodings (features templated on the real
// type, so tests can use long double), in the feature order of docs/ARCHITECTURE.md.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include "core/stage_options.hpp"

namespace mipnerf::ref {

// One IPE feature pair of degree l (mip-NeRF §3.1: the expectation of sin and cos under a
// Gaussian, E[sin(y)] = exp(−σ_y²/2)·sin(μ_y); official expected_sin): for y = 2^l·μ, v = 4^l·σ²,
// exp(−v/2)·sin(y) and exp(−v/2)·cos(y). σ² = 0 gives NeRF's PE.
template <typename T>
void ipe_pair(T mean, T var, int degree, T& sin_feature, T& cos_feature) {
  using std::cos;
  using std::exp;
  using std::ldexp;
  using std::sin;
  const T y = ldexp(mean, degree);
  const T atten = exp(T(-0.5) * ldexp(var, 2 * degree));
  sin_feature = atten * sin(y);
  cos_feature = atten * cos(y);
}

// Mirror of ipe_fwd: ipe_features [rows][6L] from means, covs [rows][3] (sines then cosines, index l·3 + axis).
void ipe_fwd(const EncodingOptions& options, const std::vector<double>& means, const std::vector<double>& covs,
             std::vector<double>& features, size_t n_rows);

// Mirror of pe_fwd (official pos_enc): features [rows][3·identity + 6L] from x [rows][3], identity first.
void pe_fwd(const EncodingOptions& options, const std::vector<double>& x, std::vector<double>& features,
            size_t n_rows);

// Mirror of gaussian_ipe_fwd: ref::gaussian_fwd then ref::ipe_fwd.
void gaussian_ipe_fwd(const GaussianOptions& gaussian_options, const EncodingOptions& options,
                      const std::vector<double>& origins, const std::vector<double>& directions,
                      const std::vector<double>& radii, const std::vector<double>& t_edges,
                      std::vector<double>& features, size_t n_rays, size_t n_samples);

// Mirror of gaussian_concat_pe_fwd (supplement §7): per row [identity] PE of the mean (degrees min..max−1), then PE
// of degrees 0..covariance_degrees−1 of the signed square roots of the full covariance's upper triangle
// (xx, xy, xz, yy, yz, zz): [6·L_cov sines] [6·L_cov cosines], index l·6 + element.
void gaussian_concat_pe_fwd(const GaussianOptions& gaussian_options, const EncodingOptions& options,
                            const std::vector<double>& origins, const std::vector<double>& directions,
                            const std::vector<double>& radii, const std::vector<double>& t_edges,
                            std::vector<double>& features, size_t n_rays, size_t n_samples);

}  // namespace mipnerf::ref
