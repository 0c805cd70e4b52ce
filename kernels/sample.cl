// Stratified sampling of interval edges along each ray (stage 2; official mip.py sample_along_rays), and the
// sorted union of two edge sets per ray (NeRF baseline's fine pass: coarse ∪ fine samples).
//
// t_edges [R][N+1]: edge k of N + 1 before jitter is
//   t_k = near·(1 − s) + far·s                    (linear in depth), or
//   t_k = 1 / ((1 − s)/near + s/far)              (SAMPLE_LINDISP: linear in disparity; near = 0 gives its limit)
// with s = k/N. Jittered (randomized != 0), edge k is drawn uniformly between the midpoints of its neighbours:
//   lower_k = k = 0 ? t_0 : (t_{k−1} + t_k)/2,   upper_k = k = N ? t_N : (t_k + t_{k+1})/2
//   edge_k = lower_k + (upper_k − lower_k)·u_k
// so the edges stay sorted and t_0, t_N stay inside [near, far]. near = far gives N empty intervals at that depth;
// far < near gives edges running from near down to far, as the official formula does (render gives such reversed
// intervals no weight: it treats δ ≤ 0 as empty). u_k is the (k mod 4)-th value of
// rng_uniform4(seed, first_ray + ray, step, k / 4, RNG_STREAM_STRATIFIED): a function of (seed, step, ray),
// whatever the chunking or device. Sampling is a constant for the gradient (no backward).

#ifndef MIPNERF_SAMPLE_CL
#define MIPNERF_SAMPLE_CL

#ifndef SAMPLE_LINDISP
#define SAMPLE_LINDISP 0
#endif

// Deterministic edge k of n_samples intervals between near and far.
// Guard (SAMPLE_LINDISP): a term whose weight is 0 (1 − s at the last edge, s at the first) is left out rather than
// evaluated as 0/0 when its bound is 0, so a zero near (or far) gives the formula's limit, 0 at every edge where
// its term has weight (near = 0: every edge but the last, which is far), instead of NaN. The official
// sample_along_rays computes 1/near·(1 − s) + 1/far·s as written, where ∞·0 makes the edge at the other end NaN
// (the last for near = 0, the first for far = 0, both for near = far = 0). For positive bounds the left-out term
// is exactly 0 anyway: the result is bit for bit the plain formula's.
// stratified_edge(near, far, k, n_samples): t_k before jitter; for k a uint and, lane by lane, a uint16 (the
// per-vector items), written once (common.cl's OVERLOADABLE): the same floats either way.
#if SAMPLE_LINDISP
#define STRATIFIED_EDGE_OF(V, s) \
  (1.0f / ((s < 1.0f ? (1.0f - s) / near : (V)0.0f) + (s > 0.0f ? s / far : (V)0.0f)))
#else
#define STRATIFIED_EDGE_OF(V, s) (near * (1.0f - s) + far * s)
#endif
#define DEFINE_STRATIFIED_EDGE(U, V, W)                                                          \
  ALWAYS_INLINE OVERLOADABLE V stratified_edge(float near, float far, U k, uint n_samples) {     \
    const V s = CONVERT_FLOAT##W(k) / (float)n_samples;                                          \
    return STRATIFIED_EDGE_OF(V, s);                                                             \
  }
DEFINE_STRATIFIED_EDGE(uint, float, )
#if VECTOR_ITEMS
DEFINE_STRATIFIED_EDGE(uint16, float16, 16)
#endif

// Edge k = 4·group + j of a ray: jittered by u (its group's draw j) unless not randomized.
#define DEFINE_STRATIFIED_JITTERED_EDGE(U, V)                                                                     \
  ALWAYS_INLINE OVERLOADABLE V stratified_jittered_edge(float t_near, float t_far, U k, uint n_samples,              \
                                                        const uint randomized, V u) {                               \
    const V t_k = stratified_edge(t_near, t_far, k, n_samples);                                                     \
    if (!randomized) return t_k;                                                                                    \
    const V lower = k == 0 ? t_k : 0.5f * (stratified_edge(t_near, t_far, k - 1, n_samples) + t_k);                 \
    const V upper = k == n_samples ? t_k : 0.5f * (t_k + stratified_edge(t_near, t_far, k + 1, n_samples));         \
    return lower + (upper - lower) * u;                                                                             \
  }
DEFINE_STRATIFIED_JITTERED_EDGE(uint, float)
#if VECTOR_ITEMS
DEFINE_STRATIFIED_JITTERED_EDGE(uint16, float16)
#endif

// One item per (ray, group of 4 edges): one Philox call gives the 4 jitters of a group. The four edges are written
// out one by one (no private array, no loop with a break: either keeps PoCL from vectorising across items).
// The kernel's items (the host's choice per device, ops/sample.hpp): SAMPLE_GROUPS_PER_VECTOR = 0, one per group of 4
// edges (one Philox call); = 1, one per 16 consecutive groups of a ray as uint16/float16 (sixteen Philox calls lane
// by lane, 64 edges; a ray's last, shorter run of groups one group at a time), which PoCL runs in full-width vector
// registers. The same edges either way, bit for bit.
#ifndef SAMPLE_GROUPS_PER_VECTOR
#define SAMPLE_GROUPS_PER_VECTOR 0
#endif

// Group `group` of ray `ray`: edges 4·group .. 4·group + 3 (those below N + 1), from one Philox call's four words.
ALWAYS_INLINE void store_edge_group(__global float* out, float t_near, float t_far, uint ray, uint group, uint n_samples,
                             const uint randomized, const ulong seed, const uint step, const uint first_ray) {
  const uint n_edges = n_samples + 1;
  uint u0 = 0, u1 = 0, u2 = 0, u3 = 0;  // the group's random words, drawn only when randomized
  if (randomized) rng_words(seed, first_ray + ray, step, group, RNG_STREAM_STRATIFIED, &u0, &u1, &u2, &u3);
  const uint k = 4 * group;
  out[k] = stratified_jittered_edge(t_near, t_far, k, n_samples, randomized, rng_uniform_of_word(u0));
  if (k + 1 < n_edges) {
    out[k + 1] = stratified_jittered_edge(t_near, t_far, k + 1, n_samples, randomized, rng_uniform_of_word(u1));
  }
  if (k + 2 < n_edges) {
    out[k + 2] = stratified_jittered_edge(t_near, t_far, k + 2, n_samples, randomized, rng_uniform_of_word(u2));
  }
  if (k + 3 < n_edges) {
    out[k + 3] = stratified_jittered_edge(t_near, t_far, k + 3, n_samples, randomized, rng_uniform_of_word(u3));
  }
}

#if SAMPLE_GROUPS_PER_VECTOR
// Groups first .. first + 15 of ray `ray` (edges 4·first .. 4·first + 63, all below N + 1): store_edge_group's
// operations lane by lane (lane = group), the four edges of each group then interleaved back into edge order.
// ALWAYS_INLINE: PoCL's inliner left it a call (cost 565 against its threshold 562, POCL_VECTORIZER_REMARKS=1);
// inlined, the sampler on one thread 0.68 → 0.59 ms (4,096 rays × 128 samples).
ALWAYS_INLINE void store_edge_groups16(__global float* out, float t_near, float t_far, uint ray, uint first,
                                       uint n_samples, const uint randomized, const ulong seed, const uint step,
                                       const uint first_ray) {
  const uint16 group = first + (uint16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  uint16 w0 = (uint16)(first_ray + ray), w1 = (uint16)(step), w2 = group, w3 = (uint16)(RNG_STREAM_STRATIFIED);
  if (randomized) philox4x32_10_words(&w0, &w1, &w2, &w3, (uint)seed, (uint)(seed >> 32));
  const uint16 k = 4 * group;
  const float16 e0 = stratified_jittered_edge(t_near, t_far, k, n_samples, randomized, rng_uniform_of_word(w0));
  const float16 e1 = stratified_jittered_edge(t_near, t_far, k + 1, n_samples, randomized, rng_uniform_of_word(w1));
  const float16 e2 = stratified_jittered_edge(t_near, t_far, k + 2, n_samples, randomized, rng_uniform_of_word(w2));
  const float16 e3 = stratified_jittered_edge(t_near, t_far, k + 3, n_samples, randomized, rng_uniform_of_word(w3));
  __global float* at = out + 4 * first;
  vstore16(((float16)(e0.s0123, e1.s0123, e2.s0123, e3.s0123)).s048c159d26ae37bf, 0, at);
  vstore16(((float16)(e0.s4567, e1.s4567, e2.s4567, e3.s4567)).s048c159d26ae37bf, 0, at + 16);
  vstore16(((float16)(e0.s89ab, e1.s89ab, e2.s89ab, e3.s89ab)).s048c159d26ae37bf, 0, at + 32);
  vstore16(((float16)(e0.scdef, e1.scdef, e2.scdef, e3.scdef)).s048c159d26ae37bf, 0, at + 48);
}
#endif

__kernel void sample_stratified_fwd(__global const float* near, __global const float* far,
                                    __global float* t_edges, const uint n_rays, const uint n_samples,
                                    const uint randomized, const ulong seed, const uint step,
                                    const uint first_ray) {
  const uint n_edges = n_samples + 1;
  const uint groups = (n_edges + 3) / 4;
  const size_t item = get_global_id(0);
#if SAMPLE_GROUPS_PER_VECTOR
  const uint runs = (groups + VECTOR_WIDTH - 1) / VECTOR_WIDTH;  // per ray
  if (item >= (size_t)n_rays * runs) return;
  const uint ray = (uint)item / runs, first = (uint)item % runs * VECTOR_WIDTH;
  __global float* out = t_edges + (size_t)ray * n_edges;
  const float t_near = near[ray], t_far = far[ray];
  if (4 * (first + VECTOR_WIDTH) <= n_edges) {
    store_edge_groups16(out, t_near, t_far, ray, first, n_samples, randomized, seed, step, first_ray);
    return;
  }
  for (uint group = first; group < groups; ++group) {
    store_edge_group(out, t_near, t_far, ray, group, n_samples, randomized, seed, step, first_ray);
  }
#else
  if (item >= (size_t)n_rays * groups) return;
  const size_t ray = item / groups;
  const uint group = (uint)(item % groups);
  store_edge_group(t_edges + ray * n_edges, near[ray], far[ray], (uint)ray, group, n_samples, randomized, seed, step,
                   first_ray);
#endif
}

// Sorted union of two sorted sets per ray: t_out [R][len_a + len_b] from t_a [R][len_a] and t_b [R][len_b]
// (a stable merge: on ties the value from t_a comes first; the values are the same either way). One item per
// ray, O(len_a + len_b).
__kernel void sample_merge_fwd(__global const float* t_a, __global const float* t_b, __global float* t_out,
                               const uint n_rays, const uint len_a, const uint len_b) {
  const size_t ray = get_global_id(0);
  if (ray >= n_rays) return;
  __global const float* a = t_a + ray * len_a;
  __global const float* b = t_b + ray * len_b;
  __global float* out = t_out + ray * (len_a + len_b);
  uint i = 0, j = 0;
  while (i < len_a || j < len_b) {
    const int take_a = j >= len_b || (i < len_a && a[i] <= b[j]);
    out[i + j] = take_a ? a[i] : b[j];
    if (take_a) ++i;
    else ++j;
  }
}

#endif
