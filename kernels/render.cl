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
// directions [R][3], comp_rgb [R][3], acc [R], distance [R], weights [R][N], d_weights [R][N].
//
// An opaque background (OPAQUE_BACKGROUND = 1; mip-NeRF 360's Model.opaque_background, multinerf
// render.compute_alpha_weights, configs/360.gin): the last interval is made infinitely thick, s_{N−1} = ∞ whatever
// its density or length, so α_{N−1} = 1, w_{N−1} = T_{N−1}, every ray's weights sum to 1 and T_N = 0. The backward
// needs no other change: its ∂L/∂s_i = g_i·(T_N + Σ_{k>i} w_k) − Σ_{k>i} g_k·w_k holds with T_N = 0 and gives 0 for
// the last sample, whose α no longer depends on its density.
//
// Density noise (DENSITY_NOISE, defined only when the noise is on; training only): the fused render_raw_* kernels
// add DENSITY_NOISE·z_i to raw density i before its activation (official models.py: `raw_density += density_noise *
// random.normal(...)` when randomized; llff.gin: 1), z_i ~ N(0, 1) keyed by (seed, step, ray index in the batch,
// level, sample): draw i % 4 of rng_normal4(seed, first_ray + ray, step, level·2^24 + i/4, RNG_STREAM_DENSITY_NOISE).
// The backward draws the same numbers again, so it differentiates the forward's noisy value; chunking does not
// change them. The plain render_fwd/bwd take activated densities and never add noise.
//
// Samples in lockstep (SAMPLES_IN_LOCKSTEP = 1; the host's choice on PoCL's CPU device, ops/render.hpp): a barrier
// ends every step of the sample loops, so all rays of a work-group take sample i before any takes i + 1. PoCL turns a
// work-group into a loop over its items and LLVM vectorises only innermost loops: with a whole ray per item that loop
// sits outside the sample loop and runs one ray at a time; the barriers split the body so the loop over items sits
// inside each step, and it vectorises across rays (a ray per vector lane; the running sums live in per-item arrays).
// Every item must then reach every barrier, so the padding items of the last work-group run the last ray again and
// store nothing (`live`). The loops hold no call (arithmetic exp and expm1, no float3 values: both stop PoCL's
// vectoriser) in either mode; without lockstep they are the same code without the barriers.
//
// Indices: rays, samples, colour values and edges are indexed with 32-bit `uint` (the host checks that 3·R·N and
// R·(N + 1) fit, ops/render.cpp). With 64-bit indices PoCL's vectoriser kept the per-sample loads and stores out of
// its vector loops ("store instruction cannot be vectorized") or made them 4 wide: on the AVX-512 Xeon render_fwd
// took 3.85 ms and render_raw_bwd 10.6 ms for 524,288 samples, 1.9 and 4.6 ms with 32-bit ones
// (bench/results/kernel_runtimes/kernel_runtimes_xeon.md).

#ifndef MIPNERF_RENDER_CL
#define MIPNERF_RENDER_CL

#define BACKGROUND_NONE 0
#define BACKGROUND_BLACK 1
#define BACKGROUND_WHITE 2
#ifndef BACKGROUND
#define BACKGROUND BACKGROUND_WHITE
#endif

#ifndef OPAQUE_BACKGROUND
#define OPAQUE_BACKGROUND 0
#endif

#ifndef SAMPLES_IN_LOCKSTEP
#define SAMPLES_IN_LOCKSTEP 0
#endif
#if SAMPLES_IN_LOCKSTEP
#define END_OF_SAMPLE_STEP() barrier(CLK_LOCAL_MEM_FENCE)
#else
#define END_OF_SAMPLE_STEP()
#endif

// Samples by vectors (SAMPLES_PER_VECTOR = 1; the host's choice on PoCL's CPU device, ops/render.hpp): a ray per
// work-item, its samples 16 at a time as float16 (loads, activations, α, T, weights, gradients: the scalar loop's
// operations lane by lane), the rest of the ray's samples (fewer than 16) by the scalar loop. PoCL runs such float16
// code as it stands in full-width vector registers, where its own vectorisation across rays (lockstep) gathers each
// sample's values from rays N floats apart, 4 at a time. Two sums go in another order, within the same float32
// bounds (tests/ops/test_render.cpp's, derived for sums in sample order): the forward's optical depth before each
// sample of a vector is the depth before the vector plus the vector's exclusive prefix sum by doubling steps (at most
// 4 + 1 roundings, against up to 15 in order), and the composite's sums (colour, acc, t·w) run per lane across the
// vectors, added pairwise at the end (⌈N/16⌉ + 4 roundings, against N). With sums in sample order the forward took
// 1.0 ms for 4,096 rays × 128 samples on the AVX-512 Xeon, 0.5 ms this way (their latency chains were the cost). The
// backward keeps the scalar loop's order (its suffix sums advance lane after lane: it was already as fast as Intel's
// runtime): given the same weights its gradients are the per-ray loop's bit for bit.
#ifndef SAMPLES_PER_VECTOR
#define SAMPLES_PER_VECTOR 0
#endif
#if SAMPLES_PER_VECTOR && SAMPLES_IN_LOCKSTEP
#error "SAMPLES_PER_VECTOR and SAMPLES_IN_LOCKSTEP are two ways of walking the samples: choose one"
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

#if SAMPLES_PER_VECTOR
// The draws of samples i .. i + 15 (i a multiple of 4), in order.
inline float16 density_noise_vector(RayNoiseKey key, uint i) {
  return (float16)(density_noise_group(key, i / 4), density_noise_group(key, i / 4 + 1),
                   density_noise_group(key, i / 4 + 2), density_noise_group(key, i / 4 + 3));
}
#endif

// noisy_raw_density(raw, z): raw density `raw` as the activation sees it: raw + DENSITY_NOISE·z (z: the sample's
// draw) with DENSITY_NOISE, else raw.
// optical_thickness(density, t0, t1, dir_norm): s_i = σ_i·δ_i. An interval of zero length contributes nothing,
// whatever its density (σ = ∞ would give ∞·0 = NaN otherwise).
// Both for float and float16 (the per-vector walk), written once (common.cl's OVERLOADABLE).
#ifdef DENSITY_NOISE
#define NOISY(raw, z) ((raw) + DENSITY_NOISE * (z))
#else
#define NOISY(raw, z) (raw)
#endif
#define DEFINE_RENDER_SAMPLE_MATH(V)                                                                    \
  ALWAYS_INLINE OVERLOADABLE V noisy_raw_density(V raw, V z) { return NOISY(raw, z); }                  \
  ALWAYS_INLINE OVERLOADABLE V optical_thickness(V density, V t0, V t1, float dir_norm) {               \
    const V delta = (t1 - t0) * dir_norm;                                                               \
    return delta > 0.0f ? density * delta : (V)0.0f;                                                    \
  }
DEFINE_RENDER_SAMPLE_MATH(float)
#if VECTOR_ITEMS
DEFINE_RENDER_SAMPLE_MATH(float16)
#endif

// s_i as the rendering takes it: ∞ for the last interval with OPAQUE_BACKGROUND, else s.
ALWAYS_INLINE float interval_thickness(float s, uint i, uint n_samples) {
  return OPAQUE_BACKGROUND && i + 1 == n_samples ? INFINITY : s;
}
#if VECTOR_ITEMS
// The same for samples i .. i + 15 (the per-vector walk).
ALWAYS_INLINE float16 interval_thickness16(float16 s, uint i, uint n_samples) {
  if (OPAQUE_BACKGROUND && i + VECTOR_WIDTH == n_samples) s.sf = INFINITY;
  return s;
}
#endif

// Density `at`: activated from a raw value with its noise draw z, or as given.
ALWAYS_INLINE float render_density(__global const float* density, uint at, float z, const int from_raw) {
  return from_raw ? density_activation(noisy_raw_density(density[at], z)) : density[at];
}

// Colour channel `c` (0..2) of sample `at`: activated from its raw value, or as given. One channel at a time: a float3
// value in the sample loop keeps PoCL from vectorising it.
ALWAYS_INLINE float render_channel(__global const float* rgb, uint at, int c, const int from_raw) {
  const float value = rgb[3 * at + c];
  return from_raw ? rgb_activation(value) : value;
}

#if SAMPLES_PER_VECTOR
// Samples at .. at + 15's densities: activated from raw values with their draws (samples i ..), or as given.
ALWAYS_INLINE float16 render_density16(__global const float* density, uint at, RayNoiseKey noise, uint i,
                                       const int from_raw) {
  const float16 value = vload16(0, density + at);
  return from_raw ? density_activation(noisy_raw_density(value, density_noise_vector(noise, i))) : value;
}
#endif

// The length of direction `ray`, which turns depth t into distance.
ALWAYS_INLINE float direction_norm(__global const float* directions, uint ray) {
  const float x = directions[3 * ray], y = directions[3 * ray + 1], z = directions[3 * ray + 2];
  return sqrt(x * x + y * y + z * z);
}

#if SAMPLES_PER_VECTOR
// Σ of a float16's lanes, pairwise (8 + 8, 4 + 4, 2 + 2, 1 + 1).
ALWAYS_INLINE float sum16(float16 v) {
  const float8 a = v.lo + v.hi;
  const float4 b = a.lo + a.hi;
  const float2 c = b.lo + b.hi;
  return c.x + c.y;
}

// Exclusive prefix sums of v's lanes: lane k holds v_0 + … + v_{k−1} (0 in lane 0), by four doubling steps
// (Hillis–Steele: each lane adds the partial sum 1, 2, 4, then 8 lanes before it), so a lane's sum has at most 4
// roundings, against k in order.
#define LANES_SHIFTED_1(v)                                                                                        \
  (float16)(0.0f, (v).s0, (v).s1, (v).s2, (v).s3, (v).s4, (v).s5, (v).s6, (v).s7, (v).s8, (v).s9, (v).sa, (v).sb, \
            (v).sc, (v).sd, (v).se)
ALWAYS_INLINE float16 exclusive_prefix_sums16(float16 v) {
  float16 x = v + LANES_SHIFTED_1(v);
  x += (float16)(0.0f, 0.0f, x.s0, x.s1, x.s2, x.s3, x.s4, x.s5, x.s6, x.s7, x.s8, x.s9, x.sa, x.sb, x.sc, x.sd);
  x += (float16)((float4)(0.0f), x.s0123, x.s4567, x.s89ab);
  x += (float16)((float8)(0.0f), x.lo);
  return LANES_SHIFTED_1(x);
}

// Running sums of the per-vector forward, lane-wise: lane k sums the samples k, k + 16, k + 32, …
typedef struct {
  float16 red, green, blue, acc, t_weighted;
} LaneSums;

// The forward pass over samples i .. i + 15 of ray `ray` (the per-vector walk): render_ray_fwd's loop for them, lane
// by lane, with the optical depth before each sample from exclusive_prefix_sums16 (then *optical_depth advances by
// the vector's sum) and the sums of the composite in `sums`.
ALWAYS_INLINE void render_vector_fwd(__global const float* rgb, __global const float* density,
                                     __global const float* t_edges, __global float* weights, const uint ray,
                                     const uint i, const uint n_samples, const float dir_norm,
                                     const RayNoiseKey noise, const int from_raw, const int with_colour,
                                     float* optical_depth, LaneSums* sums) {
  const uint at = ray * n_samples + i, t_at = ray * (n_samples + 1) + i;
  const float16 t_near = vload16(0, t_edges + t_at), t_far = vload16(0, t_edges + t_at + 1);
  const float16 s = interval_thickness16(
      optical_thickness(render_density16(density, at, noise, i, from_raw), t_near, t_far, dir_norm), i, n_samples);
  const float16 before = exclusive_prefix_sums16(s);
  const float16 depth = *optical_depth + before;  // Σ_{j<i} s_j of each lane's sample
  *optical_depth += before.sf + s.sf;
  const float16 w = -expm1_nonpositive(-s) * exp_nonpositive(-depth);
  vstore16(w, 0, weights + at);
  if (with_colour) {
    float16 r, g, b;
    load_channels16(rgb, at, &r, &g, &b);
    if (from_raw) {
      r = rgb_activation(r);
      g = rgb_activation(g);
      b = rgb_activation(b);
    }
    sums->red += w * r;
    sums->green += w * g;
    sums->blue += w * b;
  }
  sums->acc += w;
  sums->t_weighted += w * (0.5f * (t_near + t_far));
}
#endif

// The forward pass of ray `ray`; `from_raw` (a constant at each call site) applies the activations to the
// inputs first, with the ray's density noise (`noise`, used only from raw values). Writes acc, distance and weights
// (what resampling and the backward need) and, when `with_colour` (a constant at each call site), comp_rgb; without
// it rgb and comp_rgb are never touched (may be null) and the weights are the same values, computed the same way.
// Stores nothing unless `live` (see "Samples in lockstep").
ALWAYS_INLINE void render_ray_fwd(__global const float* rgb, __global const float* density,
                                  __global const float* t_edges, __global const float* directions,
                                  __global float* comp_rgb, __global float* acc_out,
                                  __global float* distance_out, __global float* weights,
                                  const uint ray, const int live, const uint n_samples, const RayNoiseKey noise,
                                  const int from_raw, const int with_colour) {
  const float dir_norm = direction_norm(directions, ray);
  const uint t_first_at = ray * (n_samples + 1);  // t_edges index of t_0
  float optical_depth = 0.0f;  // Σ_{j<i} s_j
  float red = 0.0f, green = 0.0f, blue = 0.0f;
  float acc = 0.0f, t_weighted = 0.0f;
  uint first_scalar = 0;  // the samples before it go by vectors
#if SAMPLES_PER_VECTOR
  LaneSums sums = {(float16)(0.0f), (float16)(0.0f), (float16)(0.0f), (float16)(0.0f), (float16)(0.0f)};
  for (; first_scalar + VECTOR_WIDTH <= n_samples; first_scalar += VECTOR_WIDTH) {
    render_vector_fwd(rgb, density, t_edges, weights, ray, first_scalar, n_samples, dir_norm, noise, from_raw,
                      with_colour, &optical_depth, &sums);
  }
  red = sum16(sums.red);
  green = sum16(sums.green);
  blue = sum16(sums.blue);
  acc = sum16(sums.acc);
  t_weighted = sum16(sums.t_weighted);
#endif
  float t_near = t_edges[t_first_at + first_scalar];  // t_i
  float4 draws = (float4)(0.0f);  // the noise of samples i.. to the end of i's group of 4
  for (uint i = first_scalar; i < n_samples; ++i) {
    const uint at = ray * n_samples + i;
    if (from_raw && i % 4 == 0) draws = density_noise_group(noise, i / 4);
    const float t_far = t_edges[t_first_at + i + 1];
    const float s = interval_thickness(
        optical_thickness(render_density(density, at, draws.x, from_raw), t_near, t_far, dir_norm), i, n_samples);
    draws = draws.yzwx;
    // α = 1 − exp(−s) as −expm1(−s): the same value, without cancellation for small s (official: 1 − exp).
    const float w = -expm1_nonpositive(-s) * exp_nonpositive(-optical_depth);
    if (live) weights[at] = w;
    if (with_colour) {
      red += w * render_channel(rgb, at, 0, from_raw);
      green += w * render_channel(rgb, at, 1, from_raw);
      blue += w * render_channel(rgb, at, 2, from_raw);
    }
    acc += w;
    t_weighted += w * (0.5f * (t_near + t_far));
    optical_depth += s;
    t_near = t_far;
    END_OF_SAMPLE_STEP();
  }
  if (!live) return;
  const float t_first = t_edges[t_first_at], t_last = t_edges[t_first_at + n_samples];
  const float distance = acc > 0.0f ? t_weighted / acc : t_first;
  distance_out[ray] = clamp(distance, t_first, t_last);
  acc_out[ray] = acc;
  if (!with_colour) return;
#if BACKGROUND == BACKGROUND_WHITE
  red += 1.0f - acc;
  green += 1.0f - acc;
  blue += 1.0f - acc;
#endif
  comp_rgb[3 * ray] = red;
  comp_rgb[3 * ray + 1] = green;
  comp_rgb[3 * ray + 2] = blue;
}

#if SAMPLES_PER_VECTOR
// The backward's reverse sweep over samples i .. i + 15 of ray `ray` (the per-vector walk, entered with the sums over
// the samples after them): what render_ray_bwd's loop does for them, its suffix sums advanced from the last lane to the
// first with the loop's own expressions. Without `with_colour` the weights' gradients g come from d_weights and rgb,
// d_rgb are never touched.
ALWAYS_INLINE void render_vector_bwd(__global const float* rgb, __global const float* density,
                                     __global const float* t_edges, __global const float* weights,
                                     __global const float* d_weights, __global float* d_rgb,
                                     __global float* d_density, const uint ray, const uint i, const uint n_samples,
                                     const float dir_norm, const RayNoiseKey noise, const int from_raw,
                                     const int with_colour, const float d_red, const float d_green,
                                     const float d_blue, const float d_acc_total, const uint has_d_weights,
                                     const float trans_last, float* weight_after, float* grad_weight_after) {
  const uint at = ray * n_samples + i, t_at = ray * (n_samples + 1) + i;
  const float16 w = vload16(0, weights + at);
  float16 raw_red = (float16)(0.0f), raw_green = (float16)(0.0f), raw_blue = (float16)(0.0f);
  float16 g;  // ∂L/∂w of each lane's sample
  if (with_colour) {
    load_channels16(rgb, at, &raw_red, &raw_green, &raw_blue);  // raw values when from_raw, else the colours
    const float16 red = from_raw ? rgb_activation(raw_red) : raw_red;
    const float16 green = from_raw ? rgb_activation(raw_green) : raw_green;
    const float16 blue = from_raw ? rgb_activation(raw_blue) : raw_blue;
    g = d_red * red + d_green * green + d_blue * blue + d_acc_total;
    if (has_d_weights) g += vload16(0, d_weights + at);
  } else {
    g = vload16(0, d_weights + at);
  }
  const float16 delta = (vload16(0, t_edges + t_at + 1) - vload16(0, t_edges + t_at)) * dir_norm;
  float16 w_after, gw_after;  // Σ_{k>i} w_k and Σ_{k>i} g_k·w_k of each lane's sample
#define SUFFIX_STEP(k)                   \
  w_after.s##k = *weight_after;          \
  gw_after.s##k = *grad_weight_after;    \
  *weight_after += w.s##k;               \
  *grad_weight_after += g.s##k * w.s##k;
  FOR_EACH_LANE_REVERSED(SUFFIX_STEP)
#undef SUFFIX_STEP
  const float16 d_s = g * (trans_last + w_after) - gw_after;
  float16 d_sigma = delta > 0.0f ? delta * d_s : (float16)(0.0f);
  if (from_raw) {
    d_sigma *= density_activation_grad(noisy_raw_density(vload16(0, density + at), density_noise_vector(noise, i)));
  }
  if (with_colour) {
    float16 d_red_i = d_red * w, d_green_i = d_green * w, d_blue_i = d_blue * w;  // ∂L/∂c_i
    if (from_raw) {
      d_red_i *= rgb_activation_grad(raw_red);
      d_green_i *= rgb_activation_grad(raw_green);
      d_blue_i *= rgb_activation_grad(raw_blue);
    }
    store_channels16(d_rgb, at, d_red_i, d_green_i, d_blue_i);
  }
  vstore16(d_sigma, 0, d_density + at);
}
#endif

// The backward pass of ray `ray`. With g_i = ∂L/∂w_i = d_comp·c_i + d_acc_total (d_acc_total = d_acc, minus
// Σ_c d_comp_c on a white background because comp also holds 1 − acc):
//   ∂L/∂c_i = d_comp·w_i
//   ∂L/∂s_i = g_i·T_{i+1} − Σ_{k>i} g_k·w_k     (∂w_i/∂s_i = T_{i+1}, ∂w_k/∂s_i = −w_k for k > i)
//   ∂L/∂σ_i = δ_i·∂L/∂s_i
// Evaluated in one reverse sweep with T_{i+1} = T_N + Σ_{k>i} w_k and the suffix sums accumulated as they
// go: every term is a sum of like-signed values, so the error stays relative to T_{i+1} (no exp(+s) that
// overflows, no total − prefix that cancels behind an opaque surface). T_N comes from a forward sweep of s.
// With `with_colour` (a constant at each call site) g_i comes from the composite as above, plus d_weights[ray][i] when
// has_d_weights (a loss on the weights themselves: mip-NeRF 360's distortion loss on the last level); without it
// g_i = d_weights [ray][i], given (the interlevel loss's gradient on a proposal level's weights), and rgb, d_comp_rgb,
// d_acc, d_rgb are never touched (may be null): then no colour and no background enters, as none enters the weights.
// Stores nothing unless `live`.
ALWAYS_INLINE void render_ray_bwd(__global const float* rgb, __global const float* density,
                                  __global const float* t_edges, __global const float* directions,
                                  __global const float* weights, __global const float* d_comp_rgb,
                                  __global const float* d_acc, const uint has_d_acc,
                                  __global const float* d_weights, const uint has_d_weights, __global float* d_rgb,
                                  __global float* d_density,
                                  const uint ray, const int live, const uint n_samples, const RayNoiseKey noise,
                                  const int from_raw, const int with_colour) {
  const float dir_norm = direction_norm(directions, ray);
  const uint t_first_at = ray * (n_samples + 1);  // t_edges index of t_0
  float d_red = 0.0f, d_green = 0.0f, d_blue = 0.0f, d_acc_total = 0.0f;
  if (with_colour) {
    d_red = d_comp_rgb[3 * ray];
    d_green = d_comp_rgb[3 * ray + 1];
    d_blue = d_comp_rgb[3 * ray + 2];
    d_acc_total = has_d_acc ? d_acc[ray] : 0.0f;
#if BACKGROUND == BACKGROUND_WHITE
    d_acc_total -= d_red + d_green + d_blue;
#endif
  }
  float optical_depth = 0.0f;
  const uint vector_end = SAMPLES_PER_VECTOR ? n_samples / VECTOR_WIDTH * VECTOR_WIDTH : 0;  // by vectors before it
#if SAMPLES_PER_VECTOR
  for (uint i = 0; i < vector_end; i += VECTOR_WIDTH) {
    const uint t_at = t_first_at + i;
    const float16 s = interval_thickness16(
        optical_thickness(render_density16(density, ray * n_samples + i, noise, i, from_raw),
                          vload16(0, t_edges + t_at), vload16(0, t_edges + t_at + 1), dir_norm),
        i, n_samples);
#define DEPTH_STEP(k) optical_depth += s.s##k;
    FOR_EACH_LANE(DEPTH_STEP)
#undef DEPTH_STEP
  }
#endif
  float4 draws = (float4)(0.0f);  // the forward's noise, drawn again: samples i.. to the end of i's group
  // Not a vector reduction: with 32-bit indices Intel's CPU runtime vectorised this sum along the samples for a
  // partial work-group's rays, summing in another order (T_N, and so ∂L/∂σ, then differed in the last bit from the
  // same ray's in a full group, and from render_raw_bwd's). The sum's order is the loop's.
#pragma clang loop vectorize(disable)
  for (uint i = vector_end; i < n_samples; ++i) {
    if (from_raw && i % 4 == 0) draws = density_noise_group(noise, i / 4);
    optical_depth += interval_thickness(
        optical_thickness(render_density(density, ray * n_samples + i, draws.x, from_raw), t_edges[t_first_at + i],
                          t_edges[t_first_at + i + 1], dir_norm),
        i, n_samples);
    draws = draws.yzwx;
    END_OF_SAMPLE_STEP();
  }
  const float trans_last = exp_nonpositive(-optical_depth);  // T_N
  float weight_after = 0.0f;                                 // Σ_{k>i} w_k
  float grad_weight_after = 0.0f;                            // Σ_{k>i} g_k·w_k
  for (uint r = 0; r < n_samples - vector_end; ++r) {  // the samples after the vectors', from the last
    const uint i = n_samples - 1 - r;
    const uint at = ray * n_samples + i;
    // Backwards: samples i, i − 1, .. to the start of i's group, drawn again on entering it.
    if (from_raw && (r == 0 || i % 4 == 3)) draws = density_noise_group_reversed(noise, i);
    const float w = weights[at];
    float g;  // ∂L/∂w_i
    if (with_colour) {
      const float red = render_channel(rgb, at, 0, from_raw), green = render_channel(rgb, at, 1, from_raw);
      const float blue = render_channel(rgb, at, 2, from_raw);
      g = d_red * red + d_green * green + d_blue * blue + d_acc_total;
      if (has_d_weights) g += d_weights[at];
    } else {
      g = d_weights[at];
    }
    const float delta = (t_edges[t_first_at + i + 1] - t_edges[t_first_at + i]) * dir_norm;
    const float d_s = g * (trans_last + weight_after) - grad_weight_after;
    float d_sigma = delta > 0.0f ? delta * d_s : 0.0f;
    if (from_raw) d_sigma *= density_activation_grad(noisy_raw_density(density[at], draws.x));
    if (live) d_density[at] = d_sigma;
    if (with_colour) {
      float d_red_i = d_red * w, d_green_i = d_green * w, d_blue_i = d_blue * w;  // ∂L/∂c_i
      if (from_raw) {
        d_red_i *= rgb_activation_grad(rgb[3 * at]);
        d_green_i *= rgb_activation_grad(rgb[3 * at + 1]);
        d_blue_i *= rgb_activation_grad(rgb[3 * at + 2]);
      }
      if (live) {
        d_rgb[3 * at] = d_red_i;
        d_rgb[3 * at + 1] = d_green_i;
        d_rgb[3 * at + 2] = d_blue_i;
      }
    }
    weight_after += w;
    grad_weight_after += g * w;
    draws = draws.yzwx;
    END_OF_SAMPLE_STEP();
  }
#if SAMPLES_PER_VECTOR
  for (uint i = vector_end; i > 0; i -= VECTOR_WIDTH) {
    render_vector_bwd(rgb, density, t_edges, weights, d_weights, d_rgb, d_density, ray, i - VECTOR_WIDTH, n_samples,
                      dir_norm, noise, from_raw, with_colour, d_red, d_green, d_blue, d_acc_total, has_d_weights,
                      trans_last, &weight_after, &grad_weight_after);
  }
#endif
}

// A work-item's ray, and whether it is one (`live`): the padding items past n_rays leave at once, or, with samples in
// lockstep, run the last ray again and store nothing. n_rays > 0 (the host launches nothing for zero rays).
#define RAY_OF_WORK_ITEM(n_rays)                              \
  const size_t item = get_global_id(0);                       \
  if (!SAMPLES_IN_LOCKSTEP && item >= (n_rays)) return;       \
  const int live = item < (n_rays);                           \
  const uint ray = live ? (uint)item : (n_rays) - 1

__kernel void render_fwd(__global const float* rgb, __global const float* density, __global const float* t_edges,
                         __global const float* directions, __global float* comp_rgb, __global float* acc,
                         __global float* distance, __global float* weights, const uint n_rays, const uint n_samples) {
  RAY_OF_WORK_ITEM(n_rays);
  render_ray_fwd(rgb, density, t_edges, directions, comp_rgb, acc, distance, weights, ray, live,
                 n_samples, ray_noise_key(0, 0, 0, 0), 0, 1);
}

// d_acc [R] is read only when has_d_acc != 0, d_weights [R][N] (∂L/∂w of a loss on the weights themselves, added to
// the composite's) only when has_d_weights != 0 (otherwise any buffer may be passed).
// Outputs d_rgb [R][N][3] and d_density [R][N] (overwritten, not accumulated).
__kernel void render_bwd(__global const float* rgb, __global const float* density, __global const float* t_edges,
                         __global const float* directions, __global const float* weights,
                         __global const float* d_comp_rgb, __global const float* d_acc, const uint has_d_acc,
                         __global const float* d_weights, const uint has_d_weights, __global float* d_rgb,
                         __global float* d_density, const uint n_rays, const uint n_samples) {
  RAY_OF_WORK_ITEM(n_rays);
  render_ray_bwd(rgb, density, t_edges, directions, weights, d_comp_rgb, d_acc, has_d_acc, d_weights, has_d_weights,
                 d_rgb, d_density, ray, live, n_samples, ray_noise_key(0, 0, 0, 0), 0, 1);
}

// Fused activations + rendering: the same as activations_fwd then render_fwd, reading the MLP's raw outputs
// (raw_rgb [R][N][3], raw_density [R][N]) so the activated values never go through memory. With DENSITY_NOISE the
// raw densities get their noise first, keyed by (seed, step, first_ray + ray, level); without, those are unused.
__kernel void render_raw_fwd(__global const float* raw_rgb, __global const float* raw_density,
                             __global const float* t_edges, __global const float* directions,
                             __global float* comp_rgb, __global float* acc, __global float* distance,
                             __global float* weights, const uint n_rays, const uint n_samples, const ulong seed,
                             const uint step, const uint first_ray, const uint level) {
  RAY_OF_WORK_ITEM(n_rays);
  render_ray_fwd(raw_rgb, raw_density, t_edges, directions, comp_rgb, acc, distance, weights, ray, live,
                 n_samples, ray_noise_key(seed, first_ray + ray, step, level), 1, 1);
}

// render_raw_fwd without the colour, for a level whose colour nothing reads (mip-NeRF's coarse level when rendering:
// its weights feed the fine level's resampling, its image is never shown): only the raw densities are read and only
// acc, distance and weights written, the same values render_raw_fwd writes. The MLP skips its colour head for such
// a level (mlp/network.hpp), so raw colours do not even exist here.
__kernel void render_raw_weights_fwd(__global const float* raw_density, __global const float* t_edges,
                                     __global const float* directions, __global float* acc, __global float* distance,
                                     __global float* weights, const uint n_rays, const uint n_samples,
                                     const ulong seed, const uint step, const uint first_ray, const uint level) {
  RAY_OF_WORK_ITEM(n_rays);
  render_ray_fwd(0, raw_density, t_edges, directions, 0, acc, distance, weights, ray, live, n_samples,
                 ray_noise_key(seed, first_ray + ray, step, level), 1, 0);
}

// Fused render_bwd then activations_bwd: gradients with respect to the raw outputs, d_raw_rgb [R][N][3] and
// d_raw_density [R][N]; the key must be the forward's (the same noise, drawn again).
__kernel void render_raw_bwd(__global const float* raw_rgb, __global const float* raw_density,
                             __global const float* t_edges, __global const float* directions,
                             __global const float* weights, __global const float* d_comp_rgb,
                             __global const float* d_acc, const uint has_d_acc, __global const float* d_weights,
                             const uint has_d_weights, __global float* d_raw_rgb, __global float* d_raw_density,
                             const uint n_rays, const uint n_samples, const ulong seed, const uint step,
                             const uint first_ray, const uint level) {
  RAY_OF_WORK_ITEM(n_rays);
  render_ray_bwd(raw_rgb, raw_density, t_edges, directions, weights, d_comp_rgb, d_acc, has_d_acc, d_weights,
                 has_d_weights, d_raw_rgb, d_raw_density, ray, live, n_samples,
                 ray_noise_key(seed, first_ray + ray, step, level), 1, 1);
}

// The backward of render_raw_weights_fwd's weights: from d_weights [R][N] = ∂L/∂w (what a proposal level receives
// from the interlevel loss: mip-NeRF 360's L_prop, Zip-NeRF's spline version) to d_raw_density [R][N] (overwritten),
// through the fused density activation and, with DENSITY_NOISE, at the forward's noisy value (the key must be the
// forward's). `weights` are render_raw_weights_fwd's (or render_raw_fwd's) for these inputs. Per ray, with s_i = σ_i·δ_i,
// w_i = (1 − e^{−s_i})·T_i and T_i = exp(−Σ_{j<i} s_j):
//   ∂w_i/∂s_k = T_{k+1} for i = k (T_k·e^{−s_k}), −w_i for i > k, 0 for i < k, so
//   ∂L/∂σ_k = δ_k·(g_k·T_{k+1} − Σ_{i>k} g_i·w_i),   ∂L/∂raw_k = ∂L/∂σ_k·activation'(raw_k + noise + DENSITY_BIAS)
// render_raw_bwd's sweep with g = d_weights (render_ray_bwd): O(N), T_{k+1} = T_N + Σ_{i>k} w_i with no exp(+s), so
// σ → ∞ (α = 1, T underflowing to 0 behind it; σ·δ may overflow to +∞) gives exactly 0 at and behind the opaque
// sample, all σ = 0 gives δ_k·g_k (T = 1, w = 0), and an empty interval (δ = 0) gives 0 whatever σ.
__kernel void render_raw_weights_bwd(__global const float* raw_density, __global const float* t_edges,
                                     __global const float* directions, __global const float* weights,
                                     __global const float* d_weights, __global float* d_raw_density,
                                     const uint n_rays, const uint n_samples, const ulong seed, const uint step,
                                     const uint first_ray, const uint level) {
  RAY_OF_WORK_ITEM(n_rays);
  render_ray_bwd(0, raw_density, t_edges, directions, weights, 0, 0, 0, d_weights, 0, 0, d_raw_density, ray, live,
                 n_samples, ray_noise_key(seed, first_ray + ray, step, level), 1, 0);
}

#endif
