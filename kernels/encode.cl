// Integrated positional encoding (stage 4; mip-NeRF §3.1: E[sin(y)] = exp(−σ_y²/2)·sin(μ_y) per coordinate;
// official integrated_pos_enc with diag = True), NeRF's positional encoding, and the fused Gaussian + IPE kernel.
// Needs gaussian.cl before it in the program.
//
// For each degree l = min_deg..max_deg−1 (L = max_deg − min_deg) and axis a:
//   y = 2^l·μ_a,  v = 4^l·σ²_a,  features exp(−v/2)·sin(y) and exp(−v/2)·cos(y)
// Feature order (docs/ARCHITECTURE.md; official order, which the MLP's weights depend on):
//   ipe_features [rows][6L]: the 3L sines, then the 3L cosines; inside each block index (l − min_deg)·3 + a.
//   pe features  [rows][F]:  with append_identity the 3 raw values first, then the 3L sines, then the 3L cosines
//                            (F = 3·append_identity + 6L); view directions use degrees 0..3 + identity = 27,
//                            the NeRF baseline's positions degrees 0..9 + identity = 63.
// The official code gets the cosines as sin(y + π/2); we call cos(y), the same value without the rounding of
// y + π/2 (which for |y| ~ 1e5 alone moves the argument by ~4e-3).
//
// Accuracy of large arguments (|y| up to 2^15·|μ|):
//  - y = 2^l·μ and v = 4^l·σ² are exact in float32: scaling by a power of two only changes the exponent.
//  - sin and cos are OpenCL's built-ins, which the OpenCL C specification bounds to 4 ulp over the whole float
//    range; implementations meet that with an exact (Payne–Hanek style) range reduction for large arguments. It
//    does not hold under -cl-fast-relaxed-math or with native_sin, which mipnerf-cl never uses. The test suite
//    checks the features against a long-double reference for |y| up to 2^15·100 on the test device.
//  - What remains is the error of μ itself: a float μ is within half an ulp of the true mean, and the feature is
//    exact for that float. At degree 15 one ulp of μ ~ 1 moves y by 2^15·2^−23 ≈ 0.004 rad; that is a
//    property of float32 inputs, not of the encoding, and exp(−v/2) makes those features vanish for any frustum
//    wider than ~2^−15.
// (gaussian_ipe_axis_fwd, at the end, has its own sin/cos and exp, with their bounds there.)
// The three axes go through the vector built-ins (exp, sincos on float3) without branches, which lets PoCL
// vectorise across work-items (1.7x faster than per-axis calls with a skip for zero attenuations on its CPU
// device). A zero attenuation gives 0·sin(y) = 0 for any finite y, so σ² = ∞ or 1e12 still encodes to exactly 0.

#ifndef MIPNERF_ENCODE_CL
#define MIPNERF_ENCODE_CL

// exp(−½·4^l·σ²), the IPE attenuation of degree l (scale = 2^l). Where it is below exp(−87) ≈ 1.6e−38 (about
// FLT_MIN, so a denormal or 0) it is 0: the features it scales are then within 1.6e−38 of it anyway, and exp's
// arguments stay ≥ −87. Why: at high degrees most attenuations underflow, and on PoCL's CPU device the exp of such
// arguments and the denormal products after it made the fused kernel ~2.5x slower than with them cut off
// (bench/results/kernel_runtimes/kernel_runtimes.md).
#define IPE_MIN_EXPONENT -87.0f /* attenuations below exp(IPE_MIN_EXPONENT) are 0 */

inline float3 attenuation(float3 var, float scale) {
  const float3 exponent = -0.5f * (var * (scale * scale));
  return select(exp(fmax(exponent, IPE_MIN_EXPONENT)), (float3)(0.0f), isless(exponent, (float3)(IPE_MIN_EXPONENT)));
}

// s = sin(y) and c = cos(y), for y of any float type: one sincos (the same 4-ulp bound as sin and cos). In the
// oclgrind runs (tests/oclgrind, MIPNERF_SEPARATE_SIN_COS) sin and cos apart: its uninitialised-value check cannot
// follow sincos's private pointer ("Work item needed to access private memory").
#ifdef MIPNERF_SEPARATE_SIN_COS
#define SIN_COS(y, s, c) \
  do {                   \
    (c) = cos(y);        \
    (s) = sin(y);        \
  } while (0)
#else
#define SIN_COS(y, s, c) ((s) = sincos((y), &(c)))
#endif

// Writes degree `degree`'s 3 sines at sin_out[0..2] and 3 cosines at cos_out[0..2] for mean μ, variance σ².
inline void encode_degree(float3 mean, float3 var, int degree, __global float* sin_out, __global float* cos_out) {
  const float scale = ldexp(1.0f, degree);  // 2^l, exact
  const float3 y = mean * scale;            // exact: a power-of-two scaling
  const float3 atten = attenuation(var, scale);
  float3 s, c;
  SIN_COS(y, s, c);
  vstore3(atten * s, 0, sin_out);
  vstore3(atten * c, 0, cos_out);
}

// One item per (row, degree index l): ipe_features [rows][6L] from means, covs [rows][3].
__kernel void ipe_fwd(__global const float* means, __global const float* covs, __global float* features,
                      const uint n_rows, const int min_deg, const int max_deg) {
  const uint n_degrees = (uint)(max_deg - min_deg);
  const size_t item = get_global_id(0);
  if (item >= (size_t)n_rows * n_degrees) return;
  const size_t row = item / n_degrees;
  const uint l = (uint)(item % n_degrees);
  __global float* out = features + row * 6 * n_degrees;
  encode_degree(load3(means, row), load3(covs, row), min_deg + (int)l, out + 3 * l, out + 3 * (n_degrees + l));
}

// One item per (row, degree index l), or per row when L = 0 (identity only): features [rows][F] from x [rows][3].
// The identity is written by the item of l = 0.
__kernel void pe_fwd(__global const float* x, __global float* features, const uint n_rows, const int min_deg,
                     const int max_deg, const uint append_identity) {
  const uint n_degrees = (uint)(max_deg - min_deg);
  const uint items_per_row = n_degrees > 0 ? n_degrees : 1;
  const size_t item = get_global_id(0);
  if (item >= (size_t)n_rows * items_per_row) return;
  const size_t row = item / items_per_row;
  const uint l = (uint)(item % items_per_row);
  const uint identity = append_identity ? 3 : 0;
  __global float* out = features + row * (identity + 6 * n_degrees);
  const float3 value = load3(x, row);
  if (identity && l == 0) store3(out, 0, value);
  if (n_degrees == 0) return;
  // A zero variance makes every attenuation exp(0) = 1 exactly: PE is IPE with σ² = 0, bit for bit.
  encode_degree(value, (float3)(0.0f), min_deg + (int)l, out + identity + 3 * l,
                out + identity + 3 * (n_degrees + l));
}

// Fused gaussian_fwd + ipe_fwd: ipe_features [R·N][6L] straight from the rays and edges, without writing the
// means and covariances. Tunable GAUSSIAN_IPE_PER_ROW: 1 = one item per row, which computes the Gaussian once and
// loops over the degrees (on PoCL's CPU device 2x faster than the alternative, which defeats its vectoriser);
// 0 = one item per (row, degree), each recomputing its row's Gaussian (a few flops against three sincos) for
// more, independent items with neighbouring writes (GPUs). The host picks it per device class (ops/encode.cpp).
//
// Tunable IPE_SINCOS_EVERY = K (per-row items only): one sincos every K degrees, the K − 1 degrees after it by
// the double-angle identities, as the complex square z' = z² of z = cos + i·sin:
//   sin(2y) = 2·sin(y)·cos(y),  cos(2y) = (cos(y) − sin(y))·(cos(y) + sin(y)).
// Error bound (tests/ops/test_encode.cpp checks it against long double, host mirror ref::encode_degrees too):
// let E_j be the Euclidean error of the computed (cos, sin) j doublings after a sincos. The sincos is within 4 ulp
// per component, so E_0 ≤ 8u·|z| = 8u (u = 2⁻²⁴; 4 ulp of x ≤ 4·2⁻²³·|x|). Squaring doubles an error to first
// order (|d(z²)| = 2|z||dz|) and its rounding adds at most 3u (c − s, c + s and their product: 3 roundings of a
// value ≤ 1; 2·s·c: one), so E_j ≤ 2^j·8u + (2^j − 1)·3u < 2^j·11u: for K = 4 (j ≤ 3) 88u ≈ 5.2e−6 absolute per
// feature (times its attenuation ≤ 1), against 4 ulp for a sincos per degree. The attenuations keep one exp per
// degree (repeated squaring would grow their relative error 4x per degree).
// K = 1 is a sincos per degree, bit for bit the features of the per-(row, degree) items.
#ifndef GAUSSIAN_IPE_PER_ROW
#define GAUSSIAN_IPE_PER_ROW 1
#endif

// One doubling, in place, in the order the bound above counts: (s, c) of y becomes (s, c) of 2y. A macro so the
// per-row kernel (float3) and the per-axis one (float) run the same operations.
#define DOUBLE_ANGLE(type, s, c)               \
  do {                                         \
    const type doubled_sin = 2.0f * ((s) * (c)); \
    (c) = ((c) - (s)) * ((c) + (s));           \
    (s) = doubled_sin;                         \
  } while (0)

#ifndef IPE_SINCOS_EVERY
#define IPE_SINCOS_EVERY 1
#endif

// Degrees l_begin..l_end−1 of one row (indices from min_deg), a sincos every IPE_SINCOS_EVERY degrees.
inline void encode_degrees(float3 mean, float3 var, int min_deg, uint l_begin, uint l_end, uint n_degrees,
                           __global float* out) {
  float3 s = (float3)(0.0f), c = (float3)(1.0f);
  for (uint l = l_begin; l < l_end; ++l) {
    const int degree = min_deg + (int)l;
    const float scale = ldexp(1.0f, degree);  // 2^l, exact
    if ((l - l_begin) % IPE_SINCOS_EVERY == 0) {
      SIN_COS(mean * scale, s, c);  // exact argument: a power-of-two scaling
    } else {
      DOUBLE_ANGLE(float3, s, c);
    }
    const float3 atten = attenuation(var, scale);
    vstore3(atten * s, 0, out + 3 * l);
    vstore3(atten * c, 0, out + 3 * (n_degrees + l));
  }
}

__kernel void gaussian_ipe_fwd(__global const float* origins, __global const float* directions,
                               __global const float* radii, __global const float* t_edges,
                               __global float* features, const uint n_rays, const uint n_samples,
                               const int min_deg, const int max_deg) {
  const uint n_degrees = (uint)(max_deg - min_deg);
  const size_t item = get_global_id(0);
#if GAUSSIAN_IPE_PER_ROW
  if (item >= (size_t)n_rays * n_samples) return;
  const size_t row = item;
  const uint l_begin = 0, l_end = n_degrees;
#else
  if (item >= (size_t)n_rays * n_samples * n_degrees) return;
  const size_t row = item / n_degrees;
  const uint l_begin = (uint)(item % n_degrees), l_end = l_begin + 1;
#endif
  float3 mean, cov;
  row_gaussian(origins, directions, radii, t_edges, row, n_samples, &mean, &cov);
  encode_degrees(mean, cov, min_deg, l_begin, l_end, n_degrees, features + row * 6 * n_degrees);
}

#ifdef MIPNERF_CONCAT_PE
// The concatenated-PE alternative to IPE (mip-NeRF supplement §7, Table 2), built only into the programs of a
// scene that uses it (the `mipnerf-concat-pe` variant): per row, NeRF's PE of the Gaussian's mean (degrees
// min_deg..max_deg−1, identity first if asked), then PE of degrees 0..cov_degrees−1 of
// vec(triu(sign(Σ) ∘ √|Σ|)) of the FULL 3×3 covariance (official lift_gaussian with diag = False): our IPE only
// needs the diagonal, but with it alone the three off-diagonal entries would be constant features (PE of 0), so
// this kernel lifts the off-diagonal too. Σ is symmetric, so its upper triangle is all of it; order
// (xx, xy, xz, yy, yz, zz). Paper: mean L = 12, covariance L = 2: 72 + 24 = 96 features, IPE's width.
//   features [rows][3·identity + 6L + 12·L_cov]: [identity] [3L mean sines] [3L mean cosines]
//            [6·L_cov covariance sines] [6·L_cov covariance cosines], index l·6 + element inside the last two.
// One item per row. sign(0) = 0, so a zero entry (an axis-aligned ray's off-diagonal) encodes as sin 0, cos 0.
inline float3 signed_sqrt(float3 x) { return sign(x) * sqrt(fabs(x)); }

__kernel void gaussian_concat_pe_fwd(__global const float* origins, __global const float* directions,
                                     __global const float* radii, __global const float* t_edges,
                                     __global float* features, const uint n_rays, const uint n_samples,
                                     const int min_deg, const int max_deg, const uint append_identity,
                                     const int cov_degrees) {
  const size_t row = get_global_id(0);
  if (row >= (size_t)n_rays * n_samples) return;
  float3 mean, diagonal, off;
  row_full_gaussian(origins, directions, radii, t_edges, row, n_samples, &mean, &diagonal, &off);

  const uint n_degrees = (uint)(max_deg - min_deg), identity = append_identity ? 3 : 0;
  __global float* out = features + row * (identity + 6 * n_degrees + 12 * (uint)cov_degrees);
  if (identity) store3(out, 0, mean);
  __global float* mean_pe = out + identity;
  for (uint l = 0; l < n_degrees; ++l) {
    encode_degree(mean, (float3)(0.0f), min_deg + (int)l, mean_pe + 3 * l, mean_pe + 3 * (n_degrees + l));
  }
  const float3 upper_first = signed_sqrt((float3)(diagonal.x, off.x, off.y));   // xx, xy, xz
  const float3 upper_second = signed_sqrt((float3)(diagonal.y, off.z, diagonal.z));  // yy, yz, zz
  __global float* cov_pe = mean_pe + 6 * n_degrees;
  for (int l = 0; l < cov_degrees; ++l) {
    __global float* sines = cov_pe + 6 * l;
    __global float* cosines = cov_pe + 6 * (cov_degrees + l);
    encode_degree(upper_first, (float3)(0.0f), l, sines, cosines);
    encode_degree(upper_second, (float3)(0.0f), l, sines + 3, cosines + 3);
  }
}
#endif

#ifdef IPE_AXIS_MAX_DEG
// ---- gaussian_ipe_axis_fwd: one item per (row, axis), in a program of its own (ops/encode.cpp) ----
// The per-row kernel above is a loop over degrees with float3 sincos/exp calls inside: PoCL runs it one row at a time
// (its vectoriser takes only a work-group loop with no loop or call inside). Here an item encodes one axis of one row
// with every degree IPE_AXIS_MIN_DEG..IPE_AXIS_MAX_DEG−1 unrolled (the degrees are compile-time), arithmetic only:
// sin/cos by sincos_reduced_in_double, the attenuation by exp_nonpositive (common.cl, ≤ 3 ulp, the bound OpenCL gives
// exp), a sincos every IPE_SINCOS_EVERY degrees and angle doubling between (the bound above). No float3 values and no
// consecutive same-shape loads (an item reads its own axis, so PoCL's first -O2 pass finds no x, y pair to pack into a
// <2 x float>, which its work-group vectoriser refuses). The host builds it with -cl-denorms-are-zero: features
// below FLT_MIN become 0 (|error| < 1.2e-38; the per-row kernel also cuts attenuations there) instead of taking
// the CPU's slow path for denormals. Needs fp64 (the host picks this kernel only on such devices).
#pragma OPENCL EXTENSION cl_khr_fp64 : enable

// sin(y) and cos(y) of a float y, |y| < 2^40 (|μ| < 2^25 at degree 15), each within 2 ulp (host mirror, bit for bit:
// ref::sincos_reduced_in_double):
//  - reduction y = n·π/2 + r in double: n = rint(y·2/π); π/2 = P1 + P2 + P3 (the double of π/2, the double of what
//    is left, and again; the sum is within 6e-50 of π/2). y − n·P1 is exact (y and n·P1 are multiples of 2^−52 and
//    the difference is below 1 in size, so it fits in 53 bits; for |y| < π/4, n = 0 and r = y); the next two fma round
//    once each, relative to their result; the truncation adds |n|·6e-50 < 4e-38. For every float y in [π/4, 2^40)
//    the reduced |r| ≥ 2.0e-9 (every float searched by bench/bench_sincos_reduction: closest at y = 2.19993846e10,
//    which tests/ops/test_encode.cpp encodes), so r's relative error stays below 2^−52 and the float of r is r
//    within half an ulp.
//  - |r| ≤ π/4 + 2^−12: sin by r + r³·(Taylor to r^11), cos by 1 + r²·(Taylor to r^12), Horner in r² with fma
//    (truncation below 3e-9 relative). Rounding r to float moves sin r by ≤ |r|·2^−24 < 1.12 ulp of sin r, and cos r by
//    ≤ |r|·sin|r|·2^−24 < 0.79 ulp; the polynomials themselves, over every float r in [2^−12, 0.7856] against long
//    double, are within 0.69 ulp (sin) and 0.88 ulp (cos) (the same bench), and below 2^−12 the terms past r and 1
//    are under 2^−25 relative. So ≤ 1.8 ulp (sin) and 1.7 ulp (cos); the quadrant n mod 4 swaps and negates exactly.
// That is inside the 4 ulp the tests and the doubling bound assume for a sincos. Beyond 2^40 the first reduction step
// stays exact to |y| ≈ 2^54, but no bound is claimed there.

// common.cl's round_half_even for a double: rint(x) for |x| < 2^51 (here |y·2/π| < 2^40), as (x + 1.5·2^52) − 1.5·2^52,
// one rounding to the nearest integer, ties to even.
ALWAYS_INLINE OVERLOADABLE double round_half_even(double x) { return (x + 6755399441055744.0) - 6755399441055744.0; }

// y = n·π/2 + r: sets *n and returns r, both in double.
ALWAYS_INLINE double reduce_by_half_pi(float y, double* n) {
  const double y_wide = (double)y;
  *n = round_half_even(y_wide * 0.6366197723675814);
  const double r_wide = fma(-*n, 6.123233995736766e-17, fma(-*n, 1.5707963267948966, y_wide));
  return fma(-*n, -1.4973849048591698e-33, r_wide);
}

// sin r and cos r for |r| ≲ π/4.
ALWAYS_INLINE void sincos_of_reduced(float r, float* sin_r, float* cos_r) {
  const float r2 = r * r;
  float ps = fma(r2, -2.50521084e-8f, 2.75573192e-6f);  // −1/11!, 1/9!
  ps = fma(ps, r2, -1.98412698e-4f);                      // −1/7!
  ps = fma(ps, r2, 8.33333333e-3f);                       // 1/5!
  ps = fma(ps, r2, -1.66666667e-1f);                      // −1/3!
  *sin_r = fma(r * r2, ps, r);
  float pc = fma(r2, 2.08767570e-9f, -2.75573192e-7f);  // 1/12!, −1/10!
  pc = fma(pc, r2, 2.48015873e-5f);                       // 1/8!
  pc = fma(pc, r2, -1.38888889e-3f);                      // −1/6!
  pc = fma(pc, r2, 4.16666667e-2f);                       // 1/4!
  pc = fma(pc, r2, -0.5f);
  *cos_r = fma(pc, r2, 1.0f);
}

ALWAYS_INLINE void sincos_reduced_in_double(float y, float* sin_out, float* cos_out) {
  double n;
  const float r = (float)reduce_by_half_pi(y, &n);
  float sin_r, cos_r;
  sincos_of_reduced(r, &sin_r, &cos_r);
  const int quadrant = (int)((long)n & 3);  // sin y = sin r, cos r, −sin r, −cos r for n mod 4 = 0..3
  const float sin_abs = (quadrant & 1) ? cos_r : sin_r, cos_abs = (quadrant & 1) ? sin_r : cos_r;
  *sin_out = (quadrant & 2) ? -sin_abs : sin_abs;
  *cos_out = ((quadrant + 1) & 2) ? -cos_abs : cos_abs;
}

// Row `row`'s Gaussian along `axis` (0..2): the mean and variance lift_gaussian gives that axis, computed for it
// alone. |d|² by fma from d_x² (no two same-shape products of neighbouring loads, see above); the sum of the other two
// squares in axis order as lift_gaussian adds them.
ALWAYS_INLINE void axis_gaussian(__global const float* origins, __global const float* directions,
                                 __global const float* radii, __global const float* t_edges, uint row, uint axis,
                                 uint n_samples, float* mean, float* var) {
  const uint ray = row / n_samples, i = row % n_samples, t_at = ray * (n_samples + 1) + i;
  const float3 moments = interval_moments(t_edges[t_at], t_edges[t_at + 1], radii[ray]);
  const float dx = load3_component(directions, ray, 0), dy = load3_component(directions, ray, 1);
  const float dz = load3_component(directions, ray, 2);
  const float d_mag_sq = fmax(1e-10f, fma(dz, dz, fma(dy, dy, dx * dx)));
  const float d_axis = load3_component(directions, ray, axis);
  const float d_first = axis == 0 ? dy : dx, d_second = axis == 2 ? dy : dz;  // the other two, in order
  const float null_outer = (d_first * d_first + d_second * d_second) / d_mag_sq;
  *mean = load3_component(origins, ray, axis) + moments.x * d_axis;
  *var = moments.y * (d_axis * d_axis) + moments.z * null_outer;
}

// exp(−½·4^l·σ²) as attenuation() above, from exp_nonpositive.
ALWAYS_INLINE float axis_attenuation(float var, float scale) {
  const float exponent = -0.5f * (var * (scale * scale));
  return exponent < IPE_MIN_EXPONENT ? 0.0f : exp_nonpositive(exponent);
}

#define IPE_AXIS_DEGREES (IPE_AXIS_MAX_DEG - IPE_AXIS_MIN_DEG)

// One axis of one row, every degree: features[at + 3l] = atten·sin, features[at + 3(L + l)] = atten·cos for
// l = 0..L − 1 (L = IPE_AXIS_DEGREES; `at` is the row's first feature plus the axis), a sincos every IPE_SINCOS_EVERY
// degrees. A zero variance makes every attenuation exp_nonpositive(−0) = 1 exactly: PE is IPE with σ² = 0, bit for bit.
ALWAYS_INLINE void encode_axis_degrees(float mean, float var, __global float* features, uint at) {
  float s = 0.0f, c = 1.0f;
#pragma unroll
  for (uint l = 0; l < IPE_AXIS_DEGREES; ++l) {
    const float scale = as_float((uint)(IPE_AXIS_MIN_DEG + l + 127) << 23);  // 2^degree, exact (degree ≤ 60)
    if (l % IPE_SINCOS_EVERY == 0) {
      sincos_reduced_in_double(mean * scale, &s, &c);  // exact argument: a power-of-two scaling
    } else {
      DOUBLE_ANGLE(float, s, c);
    }
    const float atten = axis_attenuation(var, scale);
    features[at + 3 * l] = atten * s;
    features[at + 3 * (IPE_AXIS_DEGREES + l)] = atten * c;
  }
}

// features [R·N][6L]: item = row·3 + axis.
__kernel void gaussian_ipe_axis_fwd(__global const float* origins, __global const float* directions,
                                    __global const float* radii, __global const float* t_edges,
                                    __global float* features, const uint n_rays, const uint n_samples) {
  const size_t item = get_global_id(0);
  if (item >= 3 * (size_t)n_rays * n_samples) return;
  const uint row = (uint)item / 3, axis = (uint)item % 3;
  float mean, var;
  axis_gaussian(origins, directions, radii, t_edges, row, axis, n_samples, &mean, &var);
  encode_axis_degrees(mean, var, features, row * 6 * IPE_AXIS_DEGREES + axis);
}

// ipe_fwd per (row, axis): features [rows][6L] from means and covs [rows][3]; item = row·3 + axis. The host builds it
// with IPE_SINCOS_EVERY = 1 (ipe_fwd's bound has no angle doubling in it).
__kernel void ipe_axis_fwd(__global const float* means, __global const float* covs, __global float* features,
                           const uint n_rows) {
  const size_t item = get_global_id(0);
  if (item >= 3 * (size_t)n_rows) return;
  const uint row = (uint)item / 3, axis = (uint)item % 3;
  encode_axis_degrees(load3_component(means, row, axis), load3_component(covs, row, axis), features,
                      row * 6 * IPE_AXIS_DEGREES + axis);
}

// pe_fwd per (row, axis): features [rows][F] from x [rows][3], F = 6L plus 3 for the identity, which comes first when
// append_identity; item = row·3 + axis. IPE_SINCOS_EVERY = 1, as ipe_axis_fwd.
__kernel void pe_axis_fwd(__global const float* x, __global float* features, const uint n_rows,
                          const uint append_identity) {
  const size_t item = get_global_id(0);
  if (item >= 3 * (size_t)n_rows) return;
  const uint row = (uint)item / 3, axis = (uint)item % 3;
  const uint identity = append_identity ? 3 : 0, row_at = row * (identity + 6 * IPE_AXIS_DEGREES);
  const float value = load3_component(x, row, axis);
  if (identity) features[row_at + axis] = value;
  encode_axis_degrees(value, 0.0f, features, row_at + identity + axis);
}
#endif

#endif
