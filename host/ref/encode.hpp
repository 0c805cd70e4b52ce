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

// Mirror of encode.cl's encode_degrees (gaussian_ipe_fwd's per-row items) for one coordinate: degrees
// min_deg..min_deg+n−1 into sin_features[l], cos_features[l], a sin/cos every `sincos_every` degrees and the others
// by the double-angle identities, in the kernel's order of operations. In double it is the exact features to
// ~1e-15; in float (T = float, std::sin/cos of the same argument) it shows the doubling's own error, which tests
// hold to the bound derived in encode.cl: < 2^j·11u per feature, j doublings after a sin/cos.
template <typename T>
void encode_degrees(T mean, T var, int min_deg, int n, int sincos_every, T* sin_features, T* cos_features) {
  using std::cos;
  using std::exp;
  using std::ldexp;
  using std::sin;
  T s = 0, c = 1;
  for (int l = 0; l < n; ++l) {
    const int degree = min_deg + l;
    const T scale = ldexp(T(1), degree);
    if (l % sincos_every == 0) {
      s = sin(mean * scale);
      c = cos(mean * scale);
    } else {
      const T doubled_sin = T(2) * (s * c);
      c = (c - s) * (c + s);
      s = doubled_sin;
    }
    const T atten = exp(T(-0.5) * (var * (scale * scale)));
    sin_features[l] = atten * s;
    cos_features[l] = atten * c;
  }
}

// The bound of encode.cl on one feature computed j doublings after a sin/cos within 4 ulp, in units of the
// feature's attenuation: 2^j·8u + (2^j − 1)·3u (u = 2⁻²⁴), 0 doublings: 8u (the sin/cos's 4 ulp, absolute).
inline double doubling_error_bound(int doublings) {
  const double u = std::ldexp(1.0, -24), growth = std::ldexp(1.0, doublings);
  return growth * 8 * u + (growth - 1) * 3 * u;
}

// Mirror of encode.cl's sincos_reduced_in_double (gaussian_ipe_axis_fwd's sin/cos), operation for operation in float
// and double, so the host computes the kernel's values bit for bit: y = n·π/2 + r in double (π/2 in three parts),
// then Taylor polynomials in float on |r| ≲ π/4, and the quadrant. encode.cl derives ≤ 2 ulp for |y| < 2^40;
// bench/bench_sincos_reduction measures the two inputs of that derivation (the smallest |r| over every float, the
// polynomials' error over every float r).
inline double reduce_by_half_pi(float y, double* n) {
  const double y_wide = static_cast<double>(y);
  // rint as the kernel's round_half_even (double) computes it (|x| < 2^51): one rounding to the nearest, ties to even.
  const double scaled = y_wide * 0.6366197723675814;
  *n = (scaled + 6755399441055744.0) - 6755399441055744.0;
  const double r_wide = std::fma(-*n, 6.123233995736766e-17, std::fma(-*n, 1.5707963267948966, y_wide));
  return std::fma(-*n, -1.4973849048591698e-33, r_wide);
}

inline void sincos_of_reduced(float r, float* sin_r, float* cos_r) {
  const float r2 = r * r;
  float ps = std::fma(r2, -2.50521084e-8f, 2.75573192e-6f);
  ps = std::fma(ps, r2, -1.98412698e-4f);
  ps = std::fma(ps, r2, 8.33333333e-3f);
  ps = std::fma(ps, r2, -1.66666667e-1f);
  *sin_r = std::fma(r * r2, ps, r);
  float pc = std::fma(r2, 2.08767570e-9f, -2.75573192e-7f);
  pc = std::fma(pc, r2, 2.48015873e-5f);
  pc = std::fma(pc, r2, -1.38888889e-3f);
  pc = std::fma(pc, r2, 4.16666667e-2f);
  pc = std::fma(pc, r2, -0.5f);
  *cos_r = std::fma(pc, r2, 1.0f);
}

inline void sincos_reduced_in_double(float y, float* sin_out, float* cos_out) {
  double n = 0;
  const float r = static_cast<float>(reduce_by_half_pi(y, &n));
  float sin_r = 0, cos_r = 0;
  sincos_of_reduced(r, &sin_r, &cos_r);
  const int quadrant = static_cast<int>(static_cast<long long>(n) & 3);
  const float sin_abs = (quadrant & 1) ? cos_r : sin_r, cos_abs = (quadrant & 1) ? sin_r : cos_r;
  *sin_out = (quadrant & 2) ? -sin_abs : sin_abs;
  *cos_out = ((quadrant + 1) & 2) ? -cos_abs : cos_abs;
}

// Mirror of ipe_fwd: ipe_features [rows][6L] from means, covs [rows][3] (sines then cosines, index l·3 + axis).
void ipe_fwd(const EncodingOptions& options, const std::vector<double>& means, const std::vector<double>& covs,
             std::vector<double>& features, size_t n_rows);

// Mirror of pe_fwd (official pos_enc): features [rows][3·identity + 6L] from x [rows][3], identity first.
void pe_fwd(const EncodingOptions& options, const std::vector<double>& x, std::vector<double>& features, size_t n_rows);

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
