// Hierarchical resampling (stage 6; mip-NeRF §3.2 and official mip.py resample_along_rays +
// math.py sorted_piecewise_constant_pdf): new sorted edges t_new [R][M+1] drawn from the coarse weights
// (M = n_new intervals; mip-NeRF draws M = N, the NeRF baseline draws its own count and merges).
//
// Per ray, with coarse edges t [N+1] and weights w [N]:
//  1. blur-pool (blur != 0): w'_i = (max(w_{i−1}, w_i) + max(w_i, w_{i+1}))/2, with w_{−1} = w_0, w_N = w_{N−1}
//     (official: a 2-tap max filter, then a 2-tap mean filter, on the edge-padded weights);
//  2. w'_i += padding (α = 0.01 in the paper; blur = 0, padding = 0 for the NeRF baseline);
//  3. if Σ w' < 1e-5, add (1e-5 − Σ w')/N to every w' (official eps: an all-zero histogram becomes uniform instead
//     of 0/0);
//  4. cdf_0 = 0, cdf_k = min(1, Σ_{i<k} w'_i / Σ w') for k = 1..N−1, cdf_N = 1;
//  5. M + 1 sorted u_j in [0, 1): deterministic u_j = j·(1 − ε)/M (numpy's linspace(0, 1 − ε, M + 1)), or
//     stratified u_j = j/(M + 1) + ξ_j·(1/(M + 1) − ε), then min(u_j, 1 − ε), with ε = 2^−23 (float32 eps) and
//     ξ_j the (j mod 4)-th value of rng_uniform4(seed, first_ray + ray, step, j / 4, RNG_STREAM_RESAMPLE);
//  6. for each u_j, k = the last index with cdf_k ≤ u_j (official: the last True of u ≥ cdf) and
//     t_new_j = t_k + clamp((u_j − cdf_k)/(cdf_{k+1} − cdf_k), 0, 1)·(t_{k+1} − t_k).
// Since u and cdf are both non-decreasing, one merge-like walk finds every k: O(N) per ray, without storing the
// CDF. The result is clamped to [t_k, t_{k+1}] so rounding cannot break sortedness. Resampling is a constant for
// the gradient (stop-gradient, as the official stop_grad = True): there is no backward.

#ifndef MIPNERF_RESAMPLE_CL
#define MIPNERF_RESAMPLE_CL

// Contraction off: the per-vector walk must round as the per-ray one does, and u = j·stratum + ξ·(stratum − ε) mixes a
// scalar and a vector product, which a compiler may fuse differently in the two.
#pragma OPENCL FP_CONTRACT OFF

#define RESAMPLE_WEIGHT_EPS 1e-5f /* official sorted_piecewise_constant_pdf eps */

// Step 1–2 for interval i of n weights w.
inline float resample_weight(__global const float* w, uint i, uint n, const uint blur, const float padding) {
  if (!blur) return w[i] + padding;
  const float left = w[i > 0 ? i - 1 : 0], mid = w[i], right = w[i + 1 < n ? i + 1 : n - 1];
  return 0.5f * (fmax(left, mid) + fmax(mid, right)) + padding;
}

// The kernel's items (the host's choice per device, ops/resample.hpp): RESAMPLE_RAYS_PER_VECTOR = 0, one per ray;
// = 1, one per 16 consecutive rays, walked together lane by lane (float16/uint16 values; each step of the walk
// advances the lanes whose u has passed their interval and keeps the others as they are). A ray's walk is
// data-dependent: one ray per item, PoCL runs it one ray at a time, its branches taken and mispredicted per ray; the
// lanes take each lane's own scalar operations in its own order, so every edge is the per-ray kernel's bit for bit.
#ifndef RESAMPLE_RAYS_PER_VECTOR
#define RESAMPLE_RAYS_PER_VECTOR 0
#endif

#if RESAMPLE_RAYS_PER_VECTOR
// p[i] for each lane's index i.
#define GATHER16(p, i)                                                                                              \
  (float16)((p)[(i).s0], (p)[(i).s1], (p)[(i).s2], (p)[(i).s3], (p)[(i).s4], (p)[(i).s5], (p)[(i).s6], (p)[(i).s7], \
            (p)[(i).s8], (p)[(i).s9], (p)[(i).sa], (p)[(i).sb], (p)[(i).sc], (p)[(i).sd], (p)[(i).se], (p)[(i).sf])

// resample_weight for each lane: interval i (each lane's own) of the n weights starting at w + base.
// ALWAYS_INLINE (with resample_rays16): PoCL's inliner left both as calls inside the walk (cost 565 against its
// threshold 562, POCL_VECTORIZER_REMARKS=1); inlined, resample_fwd on one thread 4.4 → 3.75 ms (4,096 rays).
ALWAYS_INLINE float16 resample_weight16(__global const float* w, uint16 base, uint16 i, uint n, const uint blur,
                                        const float padding) {
  const float16 mid = GATHER16(w, base + i);
  if (!blur) return mid + padding;
  const float16 left = GATHER16(w, base + select(i - 1, (uint16)(0), i == 0));
  const float16 right = GATHER16(w, base + select(i + 1, (uint16)(n - 1), i + 1 >= n));
  return 0.5f * (fmax(left, mid) + fmax(mid, right)) + padding;
}

// Rays 16·item .. 16·item + 15 (those below n_rays; the lanes past them repeat the last ray and store nothing).
ALWAYS_INLINE void resample_rays16(__global const float* t_edges, __global const float* weights,
                                   __global float* t_new, const uint first, const uint n_rays, const uint n,
                                   const uint n_new, const float padding, const uint blur, const uint randomized,
                                   const ulong seed, const uint step, const uint first_ray) {
  const uint n_out = n_new + 1;
  const uint16 lane_ray = first + (uint16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  const uint16 ray = min(lane_ray, (uint16)(n_rays - 1));
  const uint16 t_at = ray * (n + 1), w_at = ray * n, out_at = ray * n_out;
  float16 sum = 0.0f;
  for (uint i = 0; i < n; ++i) sum += resample_weight16(weights, w_at, (uint16)(i), n, blur, padding);
  const float16 extra = fmax(RESAMPLE_WEIGHT_EPS - sum, 0.0f);
  const float16 add = extra / (float)n;
  sum += extra;
  uint16 k = 0;
  float16 partial = (resample_weight16(weights, w_at, (uint16)(0), n, blur, padding) + add) / sum;
  float16 cdf_lo = 0.0f;
  float16 cdf_hi = n == 1 ? (float16)(1.0f) : fmin(partial, 1.0f);
  const float eps = FLT_EPSILON;
  const float stratum = 1.0f / (float)n_out;
  float16 xi0 = 0.0f, xi1 = 0.0f, xi2 = 0.0f, xi3 = 0.0f;  // the draws of u_j .. to the end of j's group of 4
  for (uint j = 0; j < n_out; ++j) {
    float16 u;
    if (randomized) {
      if (j % 4 == 0) {
        uint16 w0 = first_ray + ray, w1 = (uint16)(step), w2 = (uint16)(j / 4), w3 = (uint16)(RNG_STREAM_RESAMPLE);
        philox4x32_10_words(&w0, &w1, &w2, &w3, (uint)seed, (uint)(seed >> 32));
        xi0 = rng_uniform_of_word(w0);
        xi1 = rng_uniform_of_word(w1);
        xi2 = rng_uniform_of_word(w2);
        xi3 = rng_uniform_of_word(w3);
      }
      u = (float)j * stratum + xi0 * (stratum - eps);
      // The next u's draw to the front: no vector chosen by a computed index (oclgrind 21.10 mis-evaluated such a
      // choice here: every randomized edge differed from the per-ray kernel's under it, and only under it).
      xi0 = xi1;
      xi1 = xi2;
      xi2 = xi3;
    } else {
      u = (float16)((float)j * ((1.0f - eps) / (float)n_new));
    }
    u = fmin(u, 1.0f - eps);
    for (int16 advance = k + 1 < n && cdf_hi <= u; any(advance); advance = k + 1 < n && cdf_hi <= u) {
      const uint16 next = select(k, k + 1, advance);
      const float16 next_partial = partial + (resample_weight16(weights, w_at, next, n, blur, padding) + add) / sum;
      cdf_lo = select(cdf_lo, cdf_hi, advance);
      partial = select(partial, next_partial, advance);
      cdf_hi = select(cdf_hi, select(fmin(partial, 1.0f), (float16)(1.0f), next + 1 == n), advance);
      k = next;
    }
    const float16 t_lo = GATHER16(t_edges, t_at + k), t_hi = GATHER16(t_edges, t_at + k + 1);
    const float16 frac = clamp((u - cdf_lo) / (cdf_hi - cdf_lo), 0.0f, 1.0f);
    const float16 edge = clamp(t_lo + frac * (t_hi - t_lo), t_lo, t_hi);
#define STORE_LANE(l) \
    if (lane_ray.s##l < n_rays) t_new[out_at.s##l + j] = edge.s##l;
    FOR_EACH_LANE(STORE_LANE)
#undef STORE_LANE
  }
}
#endif

// One item per ray, or per 16 rays (RESAMPLE_RAYS_PER_VECTOR). t_edges [R][N+1], weights [R][N] → t_new [R][M+1]
// (M = n_new ≥ 1).
__kernel void resample_fwd(__global const float* t_edges, __global const float* weights, __global float* t_new,
                           const uint n_rays, const uint n_samples, const uint n_new, const float padding,
                           const uint blur, const uint randomized, const ulong seed, const uint step,
                           const uint first_ray) {
#if RESAMPLE_RAYS_PER_VECTOR
  const size_t item = get_global_id(0);
  if (VECTOR_WIDTH * item >= n_rays || n_samples == 0 || n_new == 0) return;
  resample_rays16(t_edges, weights, t_new, VECTOR_WIDTH * (uint)item, n_rays, n_samples, n_new, padding, blur,
                  randomized, seed, step, first_ray);
  return;
#endif
  const size_t ray = get_global_id(0);
  if (ray >= n_rays || n_samples == 0 || n_new == 0) return;
  const uint n = n_samples, n_out = n_new + 1;
  __global const float* t = t_edges + ray * (n + 1);
  __global const float* w = weights + ray * n;
  __global float* out = t_new + ray * n_out;

  float sum = 0.0f;
  for (uint i = 0; i < n; ++i) sum += resample_weight(w, i, n, blur, padding);
  const float extra = fmax(0.0f, RESAMPLE_WEIGHT_EPS - sum);
  const float add = extra / (float)n;
  sum += extra;

  // The walk: interval k spans [cdf_lo, cdf_hi]; partial = Σ_{i≤k} w'_i / Σ w' (unclamped).
  uint k = 0;
  float partial = (resample_weight(w, 0, n, blur, padding) + add) / sum;
  float cdf_lo = 0.0f;
  float cdf_hi = n == 1 ? 1.0f : fmin(partial, 1.0f);
  const float eps = FLT_EPSILON;
  const float stratum = 1.0f / (float)n_out;
  float xi[4] = {0.0f, 0.0f, 0.0f, 0.0f};
  for (uint j = 0; j < n_out; ++j) {
    float u;
    if (randomized) {
      if (j % 4 == 0) vstore4(rng_uniform4(seed, first_ray + (uint)ray, step, j / 4, RNG_STREAM_RESAMPLE), 0, xi);
      u = (float)j * stratum + xi[j % 4] * (stratum - eps);
    } else {
      u = (float)j * ((1.0f - eps) / (float)n_new);
    }
    u = fmin(u, 1.0f - eps);
    while (k + 1 < n && cdf_hi <= u) {
      ++k;
      cdf_lo = cdf_hi;
      partial += (resample_weight(w, k, n, blur, padding) + add) / sum;
      cdf_hi = k + 1 == n ? 1.0f : fmin(partial, 1.0f);
    }
    const float t_lo = t[k], t_hi = t[k + 1];
    // cdf_hi > u ≥ cdf_lo here, except at the last interval where cdf_hi = 1 > u too: the ratio is finite.
    const float frac = clamp((u - cdf_lo) / (cdf_hi - cdf_lo), 0.0f, 1.0f);
    out[j] = clamp(t_lo + frac * (t_hi - t_lo), t_lo, t_hi);
  }
}

#endif
