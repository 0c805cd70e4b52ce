// mip-NeRF 360's interlevel loss (Barron et al. 2022, eq. 13: the proposal histogram must bound the NeRF's from
// above; the official multinerf stepfun.lossfun_outer through train_utils.interlevel_loss), forward and backward.
// The loss of mip-NeRF's proposal rounds (sampler = proposal with --model mipnerf); Zip-NeRF's rounds take the
// anti-aliased spline loss instead (interlevel.cl).
//
// Per ray: the NeRF's final histogram (c, w) over N intervals and one proposal round's histogram (cp, wp) over M.
//   bound_j = Σ_{k = lo(c_j)}^{hi(c_{j+1}) − 1} wp_k                 the outer measure of NeRF interval j: every
//                                                                   proposal interval that overlaps it (eq. 12)
//   loss    = mult · mean_{rays, j} max(0, w_j − bound_j)² / (w_j + ε),  ε = FLT_EPSILON
// with stepfun.searchsorted's indices into cp [0..M]: lo(v) = the last k with cp_k ≤ v (0 when none), hi(v) = the
// first k with cp_k > v (M when none). The official forms bound_j as a difference of two cumulative sums of wp; here
// it is the sum over its own window (the same number exactly, without the cancellation that costs a small bound its
// digits in float32). (c, w) carry no gradient (the official stop_gradient onto the NeRF): the backward is ∂loss/∂wp,
//   ∂loss/∂wp_k = −scale · Σ_{j : k in window j} 2 e_j / (w_j + ε),   e_j = max(0, w_j − bound_j).
// Both edge lists are sorted along the ray, so lo(c_j) and hi(c_{j+1}) only move forward: one walk per ray.
// Reference: host/ref/interlevel_outer.hpp (same names).

// Advances the window of NeRF interval [c_lo, c_hi) over cp [M+1]: *lo to lo(c_lo), *hi to hi(c_hi). Each pointer
// only moves forward and stops at M, so a ray's walk is O(N + M) even for NaN edges (no comparison passes).
inline void outer_window(__global const float* cp, uint n_proposal, float c_lo, float c_hi, uint* lo, uint* hi) {
  while (*lo < n_proposal && cp[*lo + 1] <= c_lo) ++*lo;
  while (*hi < n_proposal && cp[*hi] <= c_hi) ++*hi;
}

inline float outer_bound(__global const float* wp, uint lo, uint hi) {
  float sum = 0.0f;
  for (uint k = lo; k < hi; ++k) sum += wp[k];
  return sum;
}

// max(0, w − bound)² / (w + ε): the half-quadratic that gives a constant gradient at bound = 0.
inline float outer_interval_loss(float w, float bound) {
  const float excess = fmax(0.0f, w - bound);
  return excess * excess / (w + FLT_EPSILON);
}

// One work-item per ray.
//   c [R][N+1], w [R][N]     the NeRF's final histogram (normalised s-distances, weights)
//   cp [R][M+1], wp [R][M]   one proposal round's histogram
//   ray_loss [R]             out: Σ_j max(0, w_j − bound_j)² / (w_j + ε); the loss is mult · Σ_rays / (R·N)
__kernel void outer_interlevel_fwd(__global const float* c, __global const float* w, __global const float* cp,
                                   __global const float* wp, __global float* ray_loss, const uint n_rays,
                                   const uint n_intervals, const uint n_proposal) {
  const uint ray = get_global_id(0);
  if (ray >= n_rays) return;
  __global const float* ray_c = c + (size_t)ray * (n_intervals + 1);
  __global const float* ray_w = w + (size_t)ray * n_intervals;
  __global const float* ray_cp = cp + (size_t)ray * (n_proposal + 1);
  __global const float* ray_wp = wp + (size_t)ray * n_proposal;
  uint lo = 0, hi = 0;
  float sum = 0.0f;
  for (uint j = 0; j < n_intervals; ++j) {
    outer_window(ray_cp, n_proposal, ray_c[j], ray_c[j + 1], &lo, &hi);
    sum += outer_interval_loss(ray_w[j], outer_bound(ray_wp, lo, hi));
  }
  ray_loss[ray] = sum;
}

// One work-item per ray: d_wp [R][M] = grad_scale · ∂(Σ_j interval loss)/∂wp, grad_scale = mult / (batch rays · N)
// times the upstream gradient. Each NeRF interval adds its −2 e_j / (w_j + ε) to every wp in its window.
__kernel void outer_interlevel_bwd(__global const float* c, __global const float* w, __global const float* cp,
                                   __global const float* wp, const float grad_scale, __global float* d_wp,
                                   const uint n_rays, const uint n_intervals, const uint n_proposal) {
  const uint ray = get_global_id(0);
  if (ray >= n_rays) return;
  __global const float* ray_c = c + (size_t)ray * (n_intervals + 1);
  __global const float* ray_w = w + (size_t)ray * n_intervals;
  __global const float* ray_cp = cp + (size_t)ray * (n_proposal + 1);
  __global const float* ray_wp = wp + (size_t)ray * n_proposal;
  __global float* ray_d_wp = d_wp + (size_t)ray * n_proposal;
  for (uint k = 0; k < n_proposal; ++k) ray_d_wp[k] = 0.0f;
  uint lo = 0, hi = 0;
  for (uint j = 0; j < n_intervals; ++j) {
    outer_window(ray_cp, n_proposal, ray_c[j], ray_c[j + 1], &lo, &hi);
    const float excess = fmax(0.0f, ray_w[j] - outer_bound(ray_wp, lo, hi));
    if (!(excess > 0.0f)) continue;
    const float g = -grad_scale * (2.0f * excess / (ray_w[j] + FLT_EPSILON));
    for (uint k = lo; k < hi; ++k) ray_d_wp[k] += g;
  }
}
