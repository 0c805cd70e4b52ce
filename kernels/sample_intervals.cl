// Proposal sampling's sampler (Zip-NeRF / mip-NeRF 360; official camp_zipnerf 8e6d57e stepfun.sample_intervals with
// the resampling logits of models.py Model.__call__): new sorted interval edges s_new [R][M+1] drawn from a previous
// level's weights, in the normalised s-space. M = n_new ≥ 2 intervals (the official refuses fewer).
//
// Per ray, with edges s [N+1] (sorted) and weights w [N]:
//  1. logits l_i = anneal · log(clip(w_i + padding, FLT_MIN, FLT_MAX)) where s_{i+1} > s_i, else −∞ (official
//     where(sdist[1:] > sdist[:-1], anneal * safe_log(weights + resample_padding), -inf): an empty interval gets no
//     mass, whatever its weight; all-zero weights give equal logits log(FLT_MIN)·anneal, so a uniform histogram);
//  2. p = softmax(l) = exp(l − max l) / Σ exp(l − max l) (jax.nn.softmax), cdf_0 = 0, cdf_k = min(1, Σ_{i<k} p_i),
//     cdf_N = 1 (integrate_weights);
//  3. M sorted u_j: deterministic (rendering) u_j = linspace(1/(2M), 1 − 1/(2M) − ε, M) (sample's
//     deterministic_center); randomised (training) u_j = j·(1 − u_max)/(M − 1) + ξ_j·max_jitter with
//     u_max = ε + (1 − ε)/M, max_jitter = (1 − u_max)/(M − 1) − ε, ξ in [0, 1) from
//     rng_uniform4(seed, first_ray + ray, step, j / 4, RNG_STREAM_PROPOSAL)[j mod 4], or ξ_0 for every j
//     (single_jitter); ε = 2^−23;
//  4. centres c_j = the inverse CDF at u_j (math.sorted_interp): k = the last index with cdf_k ≤ u_j and
//     c_j = s_k + clip((u_j − cdf_k)/max(ε², cdf_{k+1} − cdf_k), 0, 1)·(s_{k+1} − s_k);
//  5. edges: the midpoints (c_{j−1} + c_j)/2, the first and last edges the reflections 2c_0 − mid_0 and
//     2c_{M−1} − mid_{M−2} (so the end intervals are as wide as their neighbours' halves), each clipped to
//     [domain_near, domain_far] (official domain = (init_s_near, init_s_far)).
// A ray with no non-empty interval (every s equal) has only −∞ logits: the official softmax gives NaN there; we give
// every edge clip(s_0), the only point the ray has (tests/official/README.md lists the difference).
// Sampling is a constant for the gradient (the official stop_level_grad): there is no backward.

#ifndef MIPNERF_SAMPLE_INTERVALS_CL
#define MIPNERF_SAMPLE_INTERVALS_CL

#define RNG_STREAM_PROPOSAL 6u /* jitter of proposal sampling's u (rng_stream_proposal in host/core/rng.hpp) */

// Step 1 for interval i: the official's resampling logit.
inline float proposal_logit(__global const float* s, __global const float* w, uint i, const float anneal,
                            const float padding) {
  if (!(s[i + 1] > s[i])) return -INFINITY;
  // safe_log's clip: log(0) would be −∞, which must stay for the empty intervals only.
  return anneal * log(clamp(w[i] + padding, FLT_MIN, FLT_MAX));
}

// Step 3: u_j of M = n_new, given the uniform ξ of this j (ignored when deterministic).
inline float proposal_u(uint j, uint n_new, const uint randomized, float xi) {
  const float eps = FLT_EPSILON;
  const float m = (float)n_new;
  if (!randomized) {
    const float pad = 1.0f / (2.0f * m);
    return pad + (float)j * ((1.0f - pad - eps - pad) / (m - 1.0f));
  }
  const float u_max = eps + (1.0f - eps) / m;
  const float max_jitter = (1.0f - u_max) / (m - 1.0f) - eps;
  return (float)j * ((1.0f - u_max) / (m - 1.0f)) + xi * max_jitter;
}

inline float proposal_clip(float s, float domain_near, float domain_far) {
  return fmin(fmax(s, domain_near), domain_far);  // jnp.clip: minimum(maximum(x, lo), hi)
}

// One item per ray. s_edges [R][N+1], weights [R][N] → s_new [R][M+1] (N = n_intervals ≥ 1, M = n_new ≥ 2).
__kernel void sample_intervals_fwd(__global const float* s_edges, __global const float* weights,
                                   __global float* s_new, const uint n_rays, const uint n_intervals,
                                   const uint n_new, const float anneal, const float padding,
                                   const float domain_near, const float domain_far, const uint randomized,
                                   const uint single_jitter, const ulong seed, const uint step, const uint first_ray) {
  const size_t ray = get_global_id(0);
  if (ray >= n_rays || n_intervals == 0 || n_new < 2) return;
  const uint n = n_intervals, n_out = n_new + 1;
  __global const float* s = s_edges + ray * (n + 1);
  __global const float* w = weights + ray * n;
  __global float* out = s_new + ray * n_out;

  float max_logit = -INFINITY;
  for (uint i = 0; i < n; ++i) max_logit = fmax(max_logit, proposal_logit(s, w, i, anneal, padding));
  if (max_logit == -INFINITY) {  // no non-empty interval (see the header)
    for (uint j = 0; j < n_out; ++j) out[j] = proposal_clip(s[0], domain_near, domain_far);
    return;
  }
  float sum = 0.0f;
  for (uint i = 0; i < n; ++i) sum += exp(proposal_logit(s, w, i, anneal, padding) - max_logit);

  // The walk over the CDF (u and cdf both non-decreasing): interval k spans [cdf_lo, cdf_hi]; partial = Σ_{i≤k} p_i.
  uint k = 0;
  float partial = exp(proposal_logit(s, w, 0, anneal, padding) - max_logit) / sum;
  float cdf_lo = 0.0f;
  float cdf_hi = n == 1 ? 1.0f : fmin(partial, 1.0f);
  const float eps_sq = FLT_EPSILON * FLT_EPSILON;  // sorted_interp's guard against a zero-width CDF step
  float xi[4] = {0.0f, 0.0f, 0.0f, 0.0f};
  float centre_prev = 0.0f, mid_prev = 0.0f;
  for (uint j = 0; j < n_new; ++j) {
    if (randomized && (j == 0 || (!single_jitter && j % 4 == 0))) {
      vstore4(rng_uniform4(seed, first_ray + (uint)ray, step, j / 4, RNG_STREAM_PROPOSAL), 0, xi);
    }
    const float u = proposal_u(j, n_new, randomized, single_jitter ? xi[0] : xi[j % 4]);
    while (k + 1 < n && cdf_hi <= u) {
      ++k;
      cdf_lo = cdf_hi;
      partial += exp(proposal_logit(s, w, k, anneal, padding) - max_logit) / sum;
      cdf_hi = k + 1 == n ? 1.0f : fmin(partial, 1.0f);
    }
    const float s_lo = s[k], s_hi = s[k + 1];
    const float frac = clamp((u - cdf_lo) / fmax(eps_sq, cdf_hi - cdf_lo), 0.0f, 1.0f);
    // Clamped to the interval so that rounding cannot put a centre before the previous interval's last one.
    const float centre = clamp(s_lo + frac * (s_hi - s_lo), s_lo, s_hi);
    if (j > 0) {
      const float mid = (centre + centre_prev) / 2.0f;
      if (j == 1) out[0] = proposal_clip(2.0f * centre_prev - mid, domain_near, domain_far);
      out[j] = proposal_clip(mid, domain_near, domain_far);
      mid_prev = mid;
    }
    centre_prev = centre;
  }
  out[n_new] = proposal_clip(2.0f * centre_prev - mid_prev, domain_near, domain_far);
}

#ifndef RAY_DISTANCE
#define RAY_DISTANCE 0 /* RayDistance in host/core/stage_options.hpp: 0 linear, 1 power ladder, 2 reciprocal */
#endif

#if RAY_DISTANCE == 1
// The unbounded scenes' warp (camp_zipnerf configs/zipnerf/360.gin: raydist_fn = math.power_ladder and
// math.inv_power_ladder with p = −3/2, premult 2; near 0, far 1e6). power_ladder(t) = y(t) = (5/3)·(1 − h(t)) with
// h(t) = (1 + 2t/2.5)^(−3/2) (x = premult·t = 2t, xs = x/|p − 1|, |p − 1|/p = −5/3), and inv_power_ladder(y) =
// 2.5·((1 − 0.6·y)^(−2/3) − 1)/2. So with 1 − 0.6·y(t) = h(t), s_to_t(s) = inv(s·y(far) + (1 − s)·y(near)) is
//   t = 1.25·(G^(−2/3) − 1),  G = s·h(far) + (1 − s)·h(near) ∈ [h(far), h(near)] ⊂ (0, 1],
// written so that G keeps its relative precision as s → 1 (the official's 1 − 0.6·y cancels there: in float32 it would
// lose every digit of G below 2^−24). Half the samples of a uniform s lie within t = 0.73 of the origin, 90 % within
// 4.6: the cameras of a 360° capture sit at radius ≈ 1 (spherified), so the samples go where the object is and thin
// out towards the contracted background.
//
// The official's float32 constants, mirrored so that our edges are the official's to the last one (under float64 the
// rest of its arithmetic is exact by comparison):
//  - power_ladder's |p − 1|/p and inv_power_ladder's p/|p − 1| are float32 −5/3 and −0.6, whose product κ is
//    1 + 1.589e−8, not 1: the official's G is 1 − κ·(1 − G) = G − (κ − 1)·(1 − G), a shift of −1.6e−8 that moves t
//    by 1 % where G ≈ 1e−6 (t ≈ 1e4, the far background). Applied in that form (1 − κ(1 − G) would cancel in float32);
//  - inv_power_ladder clips y at minus_eps(5/3) (float32's next value below its float32 limit), which is G ≥
//    1 + (−0.6)·y_max = RAY_DISTANCE_MIN_G = 5.5631e−8: the last edge lies at t ≈ 8.58e4, whatever `far` is;
//  - its exponent 1/p is float32 −0.6666667: that one is not mirrored (G^(−2/3) by cbrt instead); it changes t by
//    at most 3.3e−7 relative (at the clip), below float32's resolution.
#define RAY_DISTANCE_KAPPA_MINUS_1 1.5894570992713852e-8f
#define RAY_DISTANCE_MIN_G 5.563100557992584e-8f

// h(t) = (1 + 2t/2.5)^(−3/2) for t ≥ 0 (b·√b overflows to ∞ past b ≈ 7e25, giving 0: beyond the clip anyway).
inline float ray_distance_h(float t) {
  const float b = 1.0f + (2.0f * t) / 2.5f;
  return 1.0f / (b * sqrt(b));
}

inline float ray_distance_s_to_t(float s, float near, float far) {
  const float g_exact = s * ray_distance_h(far) + (1.0f - s) * ray_distance_h(near);
  const float g = fmax(g_exact - RAY_DISTANCE_KAPPA_MINUS_1 * (1.0f - g_exact), RAY_DISTANCE_MIN_G);
  const float r = 1.0f / cbrt(g);  // G^(−1/3): cbrt and a reciprocal, not pow (whose bound is 16 ulp)
  return clamp(1.25f * (r * r - 1.0f), near, far);
}
#elif RAY_DISTANCE == 2
// mip-NeRF 360's warp (multinerf configs/360.gin: raydist_fn = jnp.reciprocal, near 0.2, far 1e6; the paper's eq. 11
// with g(x) = 1/x): t = 1/(s/far + (1 − s)/near), as contract.cl's ray_warp_s_to_t_of writes it (two non-negative
// terms, no cancellation), clipped to [near, far] against rounding. Uniform s is uniform in disparity 1/t: half of
// the samples lie within t = 2·near/(1 + near/far) ≈ 0.4 of the camera, the other half spread out to far.
inline float ray_distance_s_to_t(float s, float near, float far) {
  return clamp(1.0f / (s * (1.0f / far) + (1.0f - s) * (1.0f / near)), near, far);
}
#else
// The bounded scenes' identity warp (official raydist_fn = None, Blender and LLFF in NDC): t = clip(s·far + (1 − s)·near,
// near, far). The official form (not near + s·(far − near)): s = 0 and s = 1 give near and far exactly, and the clip
// keeps rounding inside [near, far].
inline float ray_distance_s_to_t(float s, float near, float far) { return clamp(s * far + (1.0f - s) * near, near, far); }
#endif

// Normalised s → metric t (official coord.construct_ray_warps' s_to_t, by RAY_DISTANCE): s [R][K] → t [R][K] with the
// ray's near [R] and far [R].
__kernel void sample_intervals_s_to_t(__global const float* s, __global const float* near, __global const float* far,
                                      __global float* t, const uint n_rays, const uint n_per_ray) {
  const size_t i = get_global_id(0);
  if (i >= (size_t)n_rays * n_per_ray) return;
  const size_t ray = i / n_per_ray;
  t[i] = ray_distance_s_to_t(s[i], near[ray], far[ray]);
}

#endif
