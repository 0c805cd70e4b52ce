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
// s_i − d > q. Its max is a sliding-window maximum: a deque of interval indices whose pdfs decrease from front to
// back (an interval entering pops every smaller one behind it, the front leaves when the window passes it), so a ray
// costs O(N) whatever the window holds (a loop over the window cost O(N²) once training concentrates a histogram's
// intervals on a surface, measured +20 % on a whole training step). The deque lives in `scratch` [R][N]. The max is
// exact, so the order of the work does not change the result. Sampling is a constant for the gradient (the official
// stop_level_grad): there is no backward.
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

inline float dilate_pdf(__global const float* s, __global const float* w, uint i) {
  return w[i] / fmax(FLT_EPSILON * FLT_EPSILON, s[i + 1] - s[i]);  // stepfun.weight_to_pdf
}

// p'(q): the largest pdf of the intervals whose dilated span [s_i − d, s_{i+1} + d) holds q. Advances the window
// [lo, hi) and the deque scratch[front..back) of its candidates (indices with decreasing pdfs).
inline float dilate_pooled_pdf(__global const float* s, __global const float* w, uint n, float d, float q, uint* lo,
                               uint* hi, __global uint* deque, uint* front, uint* back) {
  while (*hi < n && s[*hi] - d <= q) {
    const float entering = dilate_pdf(s, w, *hi);
    while (*back > *front && dilate_pdf(s, w, deque[*back - 1]) <= entering) --*back;
    deque[(*back)++] = (*hi)++;
  }
  while (*lo < n && s[*lo + 1] + d <= q) ++*lo;
  while (*front < *back && deque[*front] < *lo) ++*front;
  return *front < *back ? dilate_pdf(s, w, deque[*front]) : 0.0f;
}

// One item per ray. s_edges [R][N+1], weights [R][N] → s_out [R][3N−1], w_out [R][3N−2] (N ≥ 1); scratch [R][N].
__kernel void max_dilate_weights_fwd(__global const float* s_edges, __global const float* weights, const float dilation,
                                     const float domain_near, const float domain_far, __global float* s_out,
                                     __global float* w_out, __global uint* scratch, const uint n_rays,
                                     const uint n_intervals) {
  const size_t ray = get_global_id(0);
  if (ray >= n_rays || n_intervals == 0) return;
  const uint n = n_intervals, knots = 3 * n + 1;
  __global const float* s = s_edges + ray * (n + 1);
  __global const float* w = weights + ray * n;
  __global float* s_ray = s_out + ray * (3 * n - 1);
  __global float* w_ray = w_out + ray * (3 * n - 2);
  __global uint* deque = scratch + ray * n;
  uint a = 0, b = 0, c = 0, lo = 0, hi = 0, front = 0, back = 0;
  // The window tests the clipped knot against the unclipped spans, as the official does (clipping is monotone: the
  // clipped knots stay sorted, so the window still only moves forward).
  float q = fmin(fmax(dilate_next_knot(s, n, dilation, &a, &b, &c), domain_near), domain_far);
  float sum = 0.0f;
  for (uint k = 0; k + 1 < knots; ++k) {
    const float pdf = dilate_pooled_pdf(s, w, n, dilation, q, &lo, &hi, deque, &front, &back);
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
