// mip-NeRF 360's dilation of a proposal histogram before the next round samples from it (the official multinerf
// stepfun.max_dilate_weights with renormalize, as models.py Model.__call__ calls it for every level after the first,
// then keeps [1:-1] of its edges and weights). The paper's anti-aliasing of proposal sampling: a surface the proposal
// found between two of its edges is widened by `dilation` either side, so the next round cannot miss it.
//
// Per ray, edges s [N+1] (sorted) and weights w [N]:
//   p_i   = w_i / max(ε², s_{i+1} − s_i)                        the step pdf (stepfun.weight_to_pdf, ε = FLT_EPSILON)
//   knots = sort(s ∪ {s_i − d} ∪ {s_{i+1} + d}), clipped to [domain_near, domain_far]: 3N + 1 of them, q_0..q_3N
//   p'_k  = max {p_i : s_i − d ≤ q_k < s_{i+1} + d} (0 when none)  the pdf max-pooled over a window of ±d
//   w'_k  = p'_k (q_{k+1} − q_k), k < 3N,  then w' /= max(ε², Σ_k w'_k)
// and the output is q_1..q_{3N−1} (3N − 1 edges) with w'_1..w'_{3N−2} (3N − 2 weights), as the official slices them.
// The three edge lists are each sorted, so the knots are their merge (no sort), and as q grows the window of intervals
// whose dilated span holds it only moves forward: lo = the first i with s_{i+1} + d > q, hi = the first i with
// s_i − d > q. The max over the window is taken by a loop: a window holds ~2d/width intervals, all N only when d
// spans the ray. Sampling is a constant for the gradient (the official stop_level_grad): there is no backward.
// Reference: host/ref/dilate.hpp (same names).

// The next knot of the merge of s [N+1], s − d [N] and s[1:] + d [N], by the heads a, b, c (each advanced past it).
inline float dilate_next_knot(__global const float* s, uint n, float d, uint* a, uint* b, uint* c) {
  const float va = *a <= n ? s[*a] : INFINITY;
  const float vb = *b < n ? s[*b] - d : INFINITY;
  const float vc = *c < n ? s[*c + 1] + d : INFINITY;
  if (va <= vb && va <= vc) {
    ++*a;
    return va;
  }
  if (vb <= vc) {
    ++*b;
    return vb;
  }
  ++*c;
  return vc;
}

// p'(q): the largest pdf of the intervals whose dilated span [s_i − d, s_{i+1} + d) holds q, advancing the window.
inline float dilate_pooled_pdf(__global const float* s, __global const float* w, uint n, float d, float q, uint* lo,
                               uint* hi) {
  while (*lo < n && s[*lo + 1] + d <= q) ++*lo;
  while (*hi < n && s[*hi] - d <= q) ++*hi;
  const float eps_sq = FLT_EPSILON * FLT_EPSILON;
  float best = 0.0f;
  for (uint i = *lo; i < *hi; ++i) best = fmax(best, w[i] / fmax(eps_sq, s[i + 1] - s[i]));
  return best;
}

// One item per ray. s_edges [R][N+1], weights [R][N] → s_out [R][3N−1], w_out [R][3N−2] (N ≥ 1).
__kernel void max_dilate_weights_fwd(__global const float* s_edges, __global const float* weights, const float dilation,
                                     const float domain_near, const float domain_far, __global float* s_out,
                                     __global float* w_out, const uint n_rays, const uint n_intervals) {
  const size_t ray = get_global_id(0);
  if (ray >= n_rays || n_intervals == 0) return;
  const uint n = n_intervals, knots = 3 * n + 1;
  __global const float* s = s_edges + ray * (n + 1);
  __global const float* w = weights + ray * n;
  __global float* s_ray = s_out + ray * (3 * n - 1);
  __global float* w_ray = w_out + ray * (3 * n - 2);
  uint a = 0, b = 0, c = 0, lo = 0, hi = 0;
  // The window tests the clipped knot against the unclipped spans, as the official does (clipping is monotone: the
  // clipped knots stay sorted, so the window still only moves forward).
  float q = fmin(fmax(dilate_next_knot(s, n, dilation, &a, &b, &c), domain_near), domain_far);
  float sum = 0.0f;
  for (uint k = 0; k + 1 < knots; ++k) {
    const float pdf = dilate_pooled_pdf(s, w, n, dilation, q, &lo, &hi);
    const float q_next = fmin(fmax(dilate_next_knot(s, n, dilation, &a, &b, &c), domain_near), domain_far);
    const float weight = pdf * (q_next - q);
    sum += weight;
    if (k >= 1 && k + 2 < knots) w_ray[k - 1] = weight;
    if (k >= 1) s_ray[k - 1] = q;
    q = q_next;
  }
  const float scale = 1.0f / fmax(FLT_EPSILON * FLT_EPSILON, sum);
  for (uint k = 0; k + 2 < 3 * n; ++k) w_ray[k] *= scale;
}
