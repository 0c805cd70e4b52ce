// Conical frustum (or cylinder) → Gaussian with diagonal covariance (stage 3; mip-NeRF §3.1, supplement
// eq. 23), and point samples at interval midpoints (NeRF baseline). The inline functions are shared with
// encode.cl's fused gaussian_ipe_fwd, which must produce exactly what gaussian_fwd then ipe_fwd produce.
//
// Layouts: origins, directions [R][3]; radii [R]; t_edges [R][N+1]; means, covs [R][N][3] (rows = R·N).
// Conventions (official mip.py): `directions` are not normalised, t is measured along them, and `radii` is the
// cone's radius at t = 1 (cone) or the cylinder's radius (cylinder).

#ifndef MIPNERF_GAUSSIAN_CL
#define MIPNERF_GAUSSIAN_CL

// Contraction of a*b + c into an fma is left to the compiler by default and may differ between kernels that
// inline the same function; IPE scales means by up to 2^15, so a one-ulp difference would be visible in the
// features. Off, the Gaussian is bit-identical in gaussian_fwd and gaussian_ipe_fwd.
#pragma OPENCL FP_CONTRACT OFF

#define RAY_SHAPE_CONE 0
#define RAY_SHAPE_CYLINDER 1
#ifndef RAY_SHAPE
#define RAY_SHAPE RAY_SHAPE_CONE
#endif

// Moments along the ray: (t_mean, t_var, r_var) of one interval.
//
// Cone (supplement eq. 23), with t_μ = (t0 + t1)/2 and t_δ = (t1 − t0)/2:
//   t_mean = t_μ + 2·t_μ·t_δ² / (3t_μ² + t_δ²)
//   t_var  = t_δ²/3 − (4/15)·t_δ⁴·(12t_μ² − t_δ²) / (3t_μ² + t_δ²)²
//   r_var  = r²·(t_μ²/4 + (5/12)·t_δ² − (4/15)·t_δ⁴ / (3t_μ² + t_δ²))
// written with ratio = t_δ²/(3t_μ² + t_δ²) ∈ [0, 1] and q = (12t_μ² − t_δ²)/(3t_μ² + t_δ²) ∈ [−1, 4] so no
// intermediate (t_δ⁴, the squared denominator) overflows or underflows before the result does:
//   t_mean = t_μ·(1 + 2·ratio),  t_var = t_δ²·(1/3 − (4/15)·ratio·q),  r_var = r²·(t_μ²/4 + t_δ²·(5/12 − (4/15)·ratio))
// For t0 ≥ 0 the bracket of t_var lies in [3/20, 1/3], so there is no cancellation anywhere: the relative error is
// a few ulp whatever the width (unlike eqs. 20–22, which subtract nearly equal powers of t0 and t1).
// The denominator is 0 only for t0 = t1 = 0, where every term it divides is 0 too; the guard makes that 0/0 a 0.
// frustum_moments and cylinder_moments_of: the moments of interval(s) [t0, t1] of a ray of radius `radius`, for
// V = float and for V = float16 (gaussian_fwd's per-vector items), written once: the same operations per lane, so
// the same floats bit for bit.
#define DEFINE_INTERVAL_MOMENTS(V)                                                                                 \
  ALWAYS_INLINE OVERLOADABLE void frustum_moments(V t0, V t1, float radius, V* t_mean, V* t_var, V* r_var) {       \
    const V mu = 0.5f * (t0 + t1);                                                                                 \
    const V hw = 0.5f * (t1 - t0);                                                                                 \
    const V mu2 = mu * mu, hw2 = hw * hw;                                                                          \
    const V denom = fmax(3.0f * mu2 + hw2, FLT_MIN);                                                               \
    const V ratio = hw2 / denom;                                                                                   \
    const V q = (12.0f * mu2 - hw2) / denom;                                                                       \
    *t_mean = mu * (1.0f + 2.0f * ratio);                                                                          \
    *t_var = hw2 * (1.0f / 3.0f - (4.0f / 15.0f) * ratio * q);                                                     \
    *r_var = radius * radius * (0.25f * mu2 + hw2 * (5.0f / 12.0f - (4.0f / 15.0f) * ratio));                      \
  }                                                                                                                \
  ALWAYS_INLINE OVERLOADABLE void cylinder_moments_of(V t0, V t1, float radius, V* t_mean, V* t_var, V* r_var) {   \
    const V width = t1 - t0;                                                                                       \
    *t_mean = 0.5f * (t0 + t1);                                                                                    \
    *t_var = width * width / 12.0f;                                                                                \
    *r_var = (V)(0.25f * radius * radius);                                                                         \
  }
DEFINE_INTERVAL_MOMENTS(float)
#if VECTOR_ITEMS
DEFINE_INTERVAL_MOMENTS(float16)
#endif

inline float3 conical_frustum_moments(float t0, float t1, float radius) {
  float t_mean, t_var, r_var;
  frustum_moments(t0, t1, radius, &t_mean, &t_var, &r_var);
  return (float3)(t_mean, t_var, r_var);
}

// Cylinder of radius r (official cylinder_to_gaussian): uniform along t, uniform disc across.
inline float3 cylinder_moments(float t0, float t1, float radius) {
  float t_mean, t_var, r_var;
  cylinder_moments_of(t0, t1, radius, &t_mean, &t_var, &r_var);
  return (float3)(t_mean, t_var, r_var);
}

// Lifts the moments along the ray to a diagonal 3-D covariance (official lift_gaussian, diag = True):
//   mean = o + t_mean·d,   cov = t_var·d² + r_var·(1 − d²/|d|²)   (element-wise squares).
// 1 − d_x²/|d|² is written (d_y² + d_z²)/|d|², its exact equal without the cancellation when d is close to the
// x axis. |d|² ≥ 1e-10 as the official code clamps it (a zero direction gives a finite 0 covariance).
inline void lift_gaussian(float3 origin, float3 dir, float3 moments, float3* mean, float3* cov) {
  const float3 d2 = dir * dir;
  const float d_mag_sq = fmax(1e-10f, d2.x + d2.y + d2.z);
  const float3 null_outer = (float3)(d2.y + d2.z, d2.x + d2.z, d2.x + d2.y) / d_mag_sq;
  *mean = origin + moments.x * dir;
  *cov = moments.y * d2 + moments.z * null_outer;
}

// The off-diagonal of the full 3-D covariance (official lift_gaussian, diag = False), (Σ_xy, Σ_xz, Σ_yz):
//   Σ = t_var·d dᵀ + r_var·(I − d dᵀ/|d|²),  so  Σ_ij = (t_var − r_var/|d|²)·d_i·d_j  for i ≠ j.
// Only the concatenated-PE variant reads it (the diagonal is lift_gaussian's); IPE uses the diagonal alone.
inline float3 covariance_off_diagonal(float3 dir, float3 moments) {
  const float3 d2 = dir * dir;
  const float d_mag_sq = fmax(1e-10f, d2.x + d2.y + d2.z);
  const float along_minus_across = moments.y - moments.z / d_mag_sq;
  return along_minus_across * (float3)(dir.x * dir.y, dir.x * dir.z, dir.y * dir.z);
}

// Moments (t_mean, t_var, r_var) of interval [t0, t1] for the RAY_SHAPE this program is built with.
inline float3 interval_moments(float t0, float t1, float radius) {
#if RAY_SHAPE == RAY_SHAPE_CYLINDER
  return cylinder_moments(t0, t1, radius);
#else
  return conical_frustum_moments(t0, t1, radius);
#endif
}

// The Gaussian of interval [t0, t1] of a ray, for the RAY_SHAPE this program is built with.
inline void interval_gaussian(float3 origin, float3 dir, float radius, float t0, float t1, float3* mean,
                              float3* cov) {
  lift_gaussian(origin, dir, interval_moments(t0, t1, radius), mean, cov);
}

// The Gaussian of row = ray·N + i (interval i of `ray`).
inline void row_gaussian(__global const float* origins, __global const float* directions,
                         __global const float* radii, __global const float* t_edges, size_t row, uint n_samples,
                         float3* mean, float3* cov) {
  const size_t ray = row / n_samples, i = row % n_samples;
  __global const float* t = t_edges + ray * (n_samples + 1);
  interval_gaussian(load3(origins, ray), load3(directions, ray), radii[ray], t[i], t[i + 1], mean, cov);
}

// The full Gaussian of row = ray·N + i: mean, the diagonal and the off-diagonal (Σ_xy, Σ_xz, Σ_yz) of its covariance
// (official lift_gaussian with diag = False), what the concatenated PE and the contracted IPE start from.
inline void row_full_gaussian(__global const float* origins, __global const float* directions,
                              __global const float* radii, __global const float* t_edges, size_t row, uint n_samples,
                              float3* mean, float3* diag, float3* off) {
  const size_t ray = row / n_samples, i = row % n_samples;
  __global const float* t = t_edges + ray * (n_samples + 1);
  const float3 dir = load3(directions, ray);
  const float3 moments = interval_moments(t[i], t[i + 1], radii[ray]);
  lift_gaussian(load3(origins, ray), dir, moments, mean, diag);
  *off = covariance_off_diagonal(dir, moments);
}

// One item per row: means [R][N][3], covs [R][N][3].
// gaussian_fwd's items (the host's choice per device, ops/gaussian.hpp): GAUSSIAN_SAMPLES_PER_VECTOR = 0, one per row;
// = 1, one per 16 consecutive samples of a ray as float16 (a ray's last, shorter run of samples row by row), which
// PoCL runs in full-width vector registers where it ran the per-row kernel's float3 values an item at a time.
#ifndef GAUSSIAN_SAMPLES_PER_VECTOR
#define GAUSSIAN_SAMPLES_PER_VECTOR 0
#endif

#if GAUSSIAN_SAMPLES_PER_VECTOR
// Samples first .. first + 15 of ray `ray`: lift_gaussian's operations per lane, its per-ray terms computed as it
// computes them.
inline void store_vector_gaussian(__global const float* origins, __global const float* directions,
                                  __global const float* radii, __global const float* t_edges, __global float* means,
                                  __global float* covs, uint ray, uint first, uint n_samples) {
  __global const float* t = t_edges + ray * (n_samples + 1) + first;
  const float16 t0 = vload16(0, t), t1 = vload16(0, t + 1);
  float16 t_mean, t_var, r_var;
#if RAY_SHAPE == RAY_SHAPE_CYLINDER
  cylinder_moments_of(t0, t1, radii[ray], &t_mean, &t_var, &r_var);
#else
  frustum_moments(t0, t1, radii[ray], &t_mean, &t_var, &r_var);
#endif
  const float3 origin = load3(origins, ray), dir = load3(directions, ray);
  const float3 d2 = dir * dir;
  const float d_mag_sq = fmax(1e-10f, d2.x + d2.y + d2.z);
  const float3 null_outer = (float3)(d2.y + d2.z, d2.x + d2.z, d2.x + d2.y) / d_mag_sq;
  const uint row = ray * n_samples + first;
  store_channels16(means, row, origin.x + t_mean * dir.x, origin.y + t_mean * dir.y, origin.z + t_mean * dir.z);
  store_channels16(covs, row, t_var * d2.x + r_var * null_outer.x, t_var * d2.y + r_var * null_outer.y,
                   t_var * d2.z + r_var * null_outer.z);
}
#endif

__kernel void gaussian_fwd(__global const float* origins, __global const float* directions,
                           __global const float* radii, __global const float* t_edges, __global float* means,
                           __global float* covs, const uint n_rays, const uint n_samples) {
#if GAUSSIAN_SAMPLES_PER_VECTOR
  const uint runs = (n_samples + VECTOR_WIDTH - 1) / VECTOR_WIDTH;  // per ray
  const size_t item = get_global_id(0);
  if (item >= (size_t)n_rays * runs) return;
  const uint ray = (uint)item / runs, first = (uint)item % runs * VECTOR_WIDTH;
  if (first + VECTOR_WIDTH <= n_samples) {
    store_vector_gaussian(origins, directions, radii, t_edges, means, covs, ray, first, n_samples);
    return;
  }
  for (uint i = first; i < n_samples; ++i) {
    const size_t row = (size_t)ray * n_samples + i;
    float3 mean, cov;
    row_gaussian(origins, directions, radii, t_edges, row, n_samples, &mean, &cov);
    store3(means, row, mean);
    store3(covs, row, cov);
  }
#else
  const size_t row = get_global_id(0);
  if (row >= (size_t)n_rays * n_samples) return;
  float3 mean, cov;
  row_gaussian(origins, directions, radii, t_edges, row, n_samples, &mean, &cov);
  store3(means, row, mean);
  store3(covs, row, cov);
#endif
}

// NeRF's point samples: mean = o + t_mid·d at the interval midpoint t_mid = (t0 + t1)/2, covariance 0 (so the
// IPE of these rows is NeRF's PE). One item per row.
__kernel void gaussian_points_fwd(__global const float* origins, __global const float* directions,
                                  __global const float* t_edges, __global float* means, __global float* covs,
                                  const uint n_rays, const uint n_samples) {
  const size_t row = get_global_id(0);
  if (row >= (size_t)n_rays * n_samples) return;
  const size_t ray = row / n_samples, i = row % n_samples;
  __global const float* t = t_edges + ray * (n_samples + 1);
  const float t_mid = 0.5f * (t[i] + t[i + 1]);
  store3(means, row, load3(origins, ray) + t_mid * load3(directions, ray));
  store3(covs, row, (float3)(0.0f));
}

#endif
