// Volume rendering along each ray, forward and backward (stage 5; paper eq. 1–3 of NeRF, mip-NeRF §3).
// Needs activations.cl before it in the program (the fused render_raw_* kernels apply the activations).
//
// Per ray with edges t_0..t_N (intervals i = 0..N−1), unnormalised direction d:
//   δ_i = (t_{i+1} − t_i)·|d|            (t is depth, so |d| turns it into distance)
//   s_i = σ_i·δ_i,  α_i = 1 − exp(−s_i),  T_i = exp(−Σ_{j<i} s_j)   (exclusive cumulative sum)
//   w_i = α_i·T_i,  comp_rgb = Σ w_i·c_i (+ (1 − acc) on a white background),  acc = Σ w_i
//   distance = Σ w_i·t_mid_i / acc, clipped to [t_0, t_N]
// Official conventions (mip.py volumetric_rendering): when acc = 0 the official 0/0 becomes 0 through
// jnp.nan_to_num and the clip raises it to t_0, so distance = t_0 there; BACKGROUND_NONE and
// BACKGROUND_BLACK give the same composite (black adds 0·(1 − acc)); "none" is for premultiplied output,
// where the caller composites over its own background with acc.
// One work-item per ray, O(N), no atomics. Layouts: rgb [R][N][3], density [R][N], t_edges [R][N+1],
// directions [R][3], comp_rgb [R][3], acc [R], distance [R], weights [R][N].
//
// Density noise (DENSITY_NOISE, defined only when the noise is on; training only): the fused render_raw_* kernels
// add DENSITY_NOISE·z_i to raw density i before its activation (official models.py: `raw_density += density_noise *
// random.normal(...)` when randomized; llff.gin: 1), z_i ~ N(0, 1) keyed by (seed, step, ray index in the batch,
// level, sample): draw i % 4 of rng_normal4(seed, first_ray + ray, step, level·2^24 + i/4, RNG_STREAM_DENSITY_NOISE).
// The backward draws the same numbers again, so it differentiates the forward's noisy value; chunking does not
// change them. The plain render_fwd/bwd take activated densities and never add noise.

#ifndef MIPNERF_RENDER_CL
#define MIPNERF_RENDER_CL

#define BACKGROUND_NONE 0
#define BACKGROUND_BLACK 1
#define BACKGROUND_WHITE 2
#ifndef BACKGROUND
#define BACKGROUND BACKGROUND_WHITE
#endif

#define DENSITY_NOISE_LEVEL_SHIFT 24 /* slot = level·2^24 + sample/4: 256 levels of up to 2^26 samples */

// The key of one ray's density noise at one level: the counter's item (the ray's index in the batch), step and the
// level's first slot.
typedef struct {
  ulong seed;
  uint item, step, slot_base;
} RayNoiseKey;

inline RayNoiseKey ray_noise_key(ulong seed, uint item, uint step, uint level) {
  RayNoiseKey key;
  key.seed = seed;
  key.item = item;
  key.step = step;
  key.slot_base = level << DENSITY_NOISE_LEVEL_SHIFT;
  return key;
}

// The N(0, 1) draws of the ray's samples 4g..4g + 3 (group g), in order. The loops below draw each group once and
// take its draws one at a time from the front (`.x`, then rotate `.yzwx`): no component is chosen by a computed index
// (oclgrind 21.10 mis-evaluates such a selection in these loops). Without DENSITY_NOISE: zeros, never read.
inline float4 density_noise_group(RayNoiseKey key, uint group) {
#ifdef DENSITY_NOISE
  return rng_normal4(key.seed, key.item, key.step, key.slot_base + group, RNG_STREAM_DENSITY_NOISE);
#else
  return (float4)(0.0f);
#endif
}

// The same group's draws for a loop running backwards from sample i: sample i's draw first (`.x`), then i − 1's, down
// to the group's first sample.
inline float4 density_noise_group_reversed(RayNoiseKey key, uint i) {
  float4 reversed = density_noise_group(key, i / 4).wzyx;  // samples 4g + 3, 4g + 2, 4g + 1, 4g
  for (uint k = i % 4; k < 3; ++k) reversed = reversed.yzwx;
  return reversed;
}

// Raw density `raw` as the activation sees it: raw + DENSITY_NOISE·z (z: the sample's draw) with DENSITY_NOISE, else
// raw.
inline float noisy_raw_density(float raw, float z) {
#ifdef DENSITY_NOISE
  return raw + DENSITY_NOISE * z;
#else
  return raw;
#endif
}

// s_i = σ_i·δ_i. An interval of zero length contributes nothing, whatever its density (σ = ∞ would give
// ∞·0 = NaN otherwise).
inline float optical_thickness(float density, float t0, float t1, float dir_norm) {
  const float delta = (t1 - t0) * dir_norm;
  return delta > 0.0f ? density * delta : 0.0f;
}

// Density `at`: activated from a raw value with its noise draw z, or as given.
inline float render_density(__global const float* density, size_t at, float z, const int from_raw) {
  return from_raw ? density_activation(noisy_raw_density(density[at], z)) : density[at];
}

inline float3 render_rgb(__global const float* rgb, size_t at, const int from_raw) {
  const float3 c = load3(rgb, at);
  return from_raw ? (float3)(rgb_activation(c.x), rgb_activation(c.y), rgb_activation(c.z)) : c;
}

// The forward pass of ray `ray`; `from_raw` (a constant at each call site) applies the activations to the
// inputs first, with the ray's density noise (`noise`, used only from raw values). Writes acc, distance and weights
// (what resampling and the backward need) and, when `with_colour` (a constant at each call site), comp_rgb; without
// it rgb and comp_rgb are never touched (may be null) and the weights are the same values, computed the same way.
inline void render_ray_fwd(__global const float* rgb, __global const float* density, __global const float* t_edges,
                           __global const float* directions, __global float* comp_rgb, __global float* acc_out,
                           __global float* distance_out, __global float* weights, const size_t ray,
                           const uint n_samples, const RayNoiseKey noise, const int from_raw,
                           const int with_colour) {
  const float3 dir = load3(directions, ray);
  const float dir_norm = sqrt(dot(dir, dir));
  __global const float* t = t_edges + ray * (n_samples + 1);
  float optical_depth = 0.0f;  // Σ_{j<i} s_j
  float3 color = (float3)(0.0f);
  float acc = 0.0f, t_weighted = 0.0f;
  float4 draws = (float4)(0.0f);  // the noise of samples i.. to the end of i's group of 4
  for (uint i = 0; i < n_samples; ++i) {
    const size_t at = ray * n_samples + i;
    if (from_raw && i % 4 == 0) draws = density_noise_group(noise, i / 4);
    const float s = optical_thickness(render_density(density, at, draws.x, from_raw), t[i], t[i + 1], dir_norm);
    draws = draws.yzwx;
    // α = 1 − exp(−s) as −expm1(−s): the same value, without cancellation for small s (official: 1 − exp).
    const float w = -expm1(-s) * exp(-optical_depth);
    weights[at] = w;
    if (with_colour) color += w * render_rgb(rgb, at, from_raw);
    acc += w;
    t_weighted += w * (0.5f * (t[i] + t[i + 1]));
    optical_depth += s;
  }
  const float t_first = t[0], t_last = t[n_samples];
  const float distance = acc > 0.0f ? t_weighted / acc : t_first;
  distance_out[ray] = clamp(distance, t_first, t_last);
  acc_out[ray] = acc;
  if (!with_colour) return;
#if BACKGROUND == BACKGROUND_WHITE
  color += 1.0f - acc;
#endif
  store3(comp_rgb, ray, color);
}

// The backward pass of ray `ray`. With g_i = ∂L/∂w_i = d_comp·c_i + d_acc_total (d_acc_total = d_acc, minus
// Σ_c d_comp_c on a white background because comp also holds 1 − acc):
//   ∂L/∂c_i = d_comp·w_i
//   ∂L/∂s_i = g_i·T_{i+1} − Σ_{k>i} g_k·w_k     (∂w_i/∂s_i = T_{i+1}, ∂w_k/∂s_i = −w_k for k > i)
//   ∂L/∂σ_i = δ_i·∂L/∂s_i
// Evaluated in one reverse sweep with T_{i+1} = T_N + Σ_{k>i} w_k and the suffix sums accumulated as they
// go: every term is a sum of like-signed values, so the error stays relative to T_{i+1} (no exp(+s) that
// overflows, no total − prefix that cancels behind an opaque surface). T_N comes from a forward sweep of s.
inline void render_ray_bwd(__global const float* rgb, __global const float* density, __global const float* t_edges,
                           __global const float* directions, __global const float* weights,
                           __global const float* d_comp_rgb, __global const float* d_acc, const uint has_d_acc,
                           __global float* d_rgb, __global float* d_density, const size_t ray, const uint n_samples,
                           const RayNoiseKey noise, const int from_raw) {
  const float3 dir = load3(directions, ray);
  const float dir_norm = sqrt(dot(dir, dir));
  __global const float* t = t_edges + ray * (n_samples + 1);
  const float3 d_comp = load3(d_comp_rgb, ray);
  float d_acc_total = has_d_acc ? d_acc[ray] : 0.0f;
#if BACKGROUND == BACKGROUND_WHITE
  d_acc_total -= d_comp.x + d_comp.y + d_comp.z;
#endif
  float optical_depth = 0.0f;
  float4 draws = (float4)(0.0f);  // the forward's noise, drawn again: samples i.. to the end of i's group
  for (uint i = 0; i < n_samples; ++i) {
    if (from_raw && i % 4 == 0) draws = density_noise_group(noise, i / 4);
    optical_depth +=
        optical_thickness(render_density(density, ray * n_samples + i, draws.x, from_raw), t[i], t[i + 1], dir_norm);
    draws = draws.yzwx;
  }
  const float trans_last = exp(-optical_depth);  // T_N
  float weight_after = 0.0f;                     // Σ_{k>i} w_k
  float grad_weight_after = 0.0f;                // Σ_{k>i} g_k·w_k
  for (uint r = 0; r < n_samples; ++r) {
    const uint i = n_samples - 1 - r;
    const size_t at = ray * n_samples + i;
    // Backwards: samples i, i − 1, .. to the start of i's group, drawn again on entering it.
    if (from_raw && (r == 0 || i % 4 == 3)) draws = density_noise_group_reversed(noise, i);
    const float w = weights[at];
    const float3 c = render_rgb(rgb, at, from_raw);
    const float g = dot(d_comp, c) + d_acc_total;
    const float3 d_c = d_comp * w;
    const float delta = (t[i + 1] - t[i]) * dir_norm;
    const float d_s = g * (trans_last + weight_after) - grad_weight_after;
    float d_sigma = delta > 0.0f ? delta * d_s : 0.0f;
    if (from_raw) {
      d_sigma *= density_activation_grad(noisy_raw_density(density[at], draws.x));
      const float3 raw = load3(rgb, at);
      store3(d_rgb, at,
             d_c * (float3)(rgb_activation_grad(raw.x), rgb_activation_grad(raw.y), rgb_activation_grad(raw.z)));
    } else {
      store3(d_rgb, at, d_c);
    }
    d_density[at] = d_sigma;
    weight_after += w;
    grad_weight_after += g * w;
    draws = draws.yzwx;
  }
}

__kernel void render_fwd(__global const float* rgb, __global const float* density, __global const float* t_edges,
                         __global const float* directions, __global float* comp_rgb, __global float* acc,
                         __global float* distance, __global float* weights, const uint n_rays, const uint n_samples) {
  const size_t ray = get_global_id(0);
  if (ray >= n_rays) return;
  render_ray_fwd(rgb, density, t_edges, directions, comp_rgb, acc, distance, weights, ray, n_samples,
                 ray_noise_key(0, 0, 0, 0), 0, 1);
}

// d_acc [R] is read only when has_d_acc != 0 (otherwise any buffer may be passed).
// Outputs d_rgb [R][N][3] and d_density [R][N] (overwritten, not accumulated).
__kernel void render_bwd(__global const float* rgb, __global const float* density, __global const float* t_edges,
                         __global const float* directions, __global const float* weights,
                         __global const float* d_comp_rgb, __global const float* d_acc, const uint has_d_acc,
                         __global float* d_rgb, __global float* d_density, const uint n_rays, const uint n_samples) {
  const size_t ray = get_global_id(0);
  if (ray >= n_rays) return;
  render_ray_bwd(rgb, density, t_edges, directions, weights, d_comp_rgb, d_acc, has_d_acc, d_rgb, d_density, ray,
                 n_samples, ray_noise_key(0, 0, 0, 0), 0);
}

// Fused activations + rendering: the same as activations_fwd then render_fwd, reading the MLP's raw outputs
// (raw_rgb [R][N][3], raw_density [R][N]) so the activated values never go through memory. With DENSITY_NOISE the
// raw densities get their noise first, keyed by (seed, step, first_ray + ray, level); without, those are unused.
__kernel void render_raw_fwd(__global const float* raw_rgb, __global const float* raw_density,
                             __global const float* t_edges, __global const float* directions,
                             __global float* comp_rgb, __global float* acc, __global float* distance,
                             __global float* weights, const uint n_rays, const uint n_samples, const ulong seed,
                             const uint step, const uint first_ray, const uint level) {
  const size_t ray = get_global_id(0);
  if (ray >= n_rays) return;
  render_ray_fwd(raw_rgb, raw_density, t_edges, directions, comp_rgb, acc, distance, weights, ray, n_samples,
                 ray_noise_key(seed, first_ray + (uint)ray, step, level), 1, 1);
}

// render_raw_fwd without the colour, for a level whose colour nothing reads (mip-NeRF's coarse level when rendering:
// its weights feed the fine level's resampling, its image is never shown): only the raw densities are read and only
// acc, distance and weights written, the same values render_raw_fwd writes. The MLP skips its colour head for such
// a level (mlp/network.hpp), so raw colours do not even exist here.
__kernel void render_raw_weights_fwd(__global const float* raw_density, __global const float* t_edges,
                                     __global const float* directions, __global float* acc, __global float* distance,
                                     __global float* weights, const uint n_rays, const uint n_samples,
                                     const ulong seed, const uint step, const uint first_ray, const uint level) {
  const size_t ray = get_global_id(0);
  if (ray >= n_rays) return;
  render_ray_fwd(0, raw_density, t_edges, directions, 0, acc, distance, weights, ray, n_samples,
                 ray_noise_key(seed, first_ray + (uint)ray, step, level), 1, 0);
}

// Fused render_bwd then activations_bwd: gradients with respect to the raw outputs, d_raw_rgb [R][N][3] and
// d_raw_density [R][N]; the key must be the forward's (the same noise, drawn again).
__kernel void render_raw_bwd(__global const float* raw_rgb, __global const float* raw_density,
                             __global const float* t_edges, __global const float* directions,
                             __global const float* weights, __global const float* d_comp_rgb,
                             __global const float* d_acc, const uint has_d_acc, __global float* d_raw_rgb,
                             __global float* d_raw_density, const uint n_rays, const uint n_samples, const ulong seed,
                             const uint step, const uint first_ray, const uint level) {
  const size_t ray = get_global_id(0);
  if (ray >= n_rays) return;
  render_ray_bwd(raw_rgb, raw_density, t_edges, directions, weights, d_comp_rgb, d_acc, has_d_acc, d_raw_rgb,
                 d_raw_density, ray, n_samples, ray_noise_key(seed, first_ray + (uint)ray, step, level), 1);
}

#endif
