// Activations of the MLP's raw outputs, forward and backward (stage 7), as inline functions that other
// kernels share (render.cl's fused render_raw_* kernels) and as two element-wise kernels.
//
//   density = softplus(raw + DENSITY_BIAS)            mip-NeRF (official: density_bias = −1)
//           = relu(raw + DENSITY_BIAS)                NeRF baseline (bias 0)
//   rgb     = (1 + 2ε)·sigmoid(raw) − ε, ε = RGB_PADDING   mip-NeRF's widened sigmoid (ε = 0.001);
//                                                     ε = 0 is NeRF's plain sigmoid.
// Layouts: raw_density, density [rows]; raw_rgb, rgb [rows][3] (docs/ARCHITECTURE.md).

#ifndef MIPNERF_ACTIVATIONS_CL
#define MIPNERF_ACTIVATIONS_CL

#define DENSITY_ACTIVATION_SOFTPLUS 0
#define DENSITY_ACTIVATION_RELU 1
#ifndef DENSITY_ACTIVATION
#define DENSITY_ACTIVATION DENSITY_ACTIVATION_SOFTPLUS
#endif
#ifndef DENSITY_BIAS
#define DENSITY_BIAS -1.0f
#endif
#ifndef RGB_PADDING
#define RGB_PADDING 0.001f
#endif

// sigmoid(x) = 1/(1 + e^−x), evaluated through e = exp(−|x|) ≤ 1 so nothing overflows at |x| = 1e4 and the
// small side keeps its relative accuracy (e/(1 + e) instead of 1 − 1/(1 + e^|x|)).
ALWAYS_INLINE float stable_sigmoid(float x) {
  const float e = exp_nonpositive(-fabs(x));
  return x >= 0.0f ? 1.0f / (1.0f + e) : e / (1.0f + e);
}

// sigmoid'(x) = sigmoid(x)·(1 − sigmoid(x)) = e/(1 + e)², e = exp(−|x|): even in x, finite everywhere, and
// accurate where 1 − sigmoid(x) would round to 0 (x > 17).
ALWAYS_INLINE float stable_sigmoid_grad(float x) {
  const float e = exp_nonpositive(-fabs(x));
  const float one_plus_e = 1.0f + e;
  return e / (one_plus_e * one_plus_e);
}

// softplus(x) = log(1 + e^x) = max(x, 0) + log1p(e^−|x|): no overflow for large x (official uses
// jax.nn.softplus, which is computed the same way), no cancellation for very negative x.
ALWAYS_INLINE float stable_softplus(float x) { return fmax(x, 0.0f) + log1p_unit(exp_nonpositive(-fabs(x))); }

ALWAYS_INLINE float density_activation(float raw) {
  const float x = raw + DENSITY_BIAS;
#if DENSITY_ACTIVATION == DENSITY_ACTIVATION_RELU
  return fmax(x, 0.0f);
#else
  return stable_softplus(x);
#endif
}

// d density / d raw: softplus' = sigmoid; relu' = 1 for x > 0 and 0 otherwise (0 at x = 0, as JAX's relu).
ALWAYS_INLINE float density_activation_grad(float raw) {
  const float x = raw + DENSITY_BIAS;
#if DENSITY_ACTIVATION == DENSITY_ACTIVATION_RELU
  return x > 0.0f ? 1.0f : 0.0f;
#else
  return stable_sigmoid(x);
#endif
}

ALWAYS_INLINE float rgb_activation(float raw) { return (1.0f + 2.0f * RGB_PADDING) * stable_sigmoid(raw) - RGB_PADDING; }

ALWAYS_INLINE float rgb_activation_grad(float raw) { return (1.0f + 2.0f * RGB_PADDING) * stable_sigmoid_grad(raw); }

// The element-wise kernels' items (the host chooses per device, ops/activations.hpp): ACTIVATION_ITEM_PER_ROW = 0,
// one item per value: the colour values' items first (flat index j of rgb), padded to whole work-groups, then one
// item per density from the next work-group on. PoCL vectorises across work-items, and a row's three interleaved
// colour values (stride 3) kept its vectoriser from vectorising at all (17 ms against 6 ms for 524,288 rows on its
// CPU device). A work-group holds only colour or only density items, decided by its group id, which PoCL's loop over
// the group's items sees as invariant: each vector runs one activation, where items doing a colour value and (the
// first `rows`) a density too ran both in every vector, masked (3.4 against 2.3 ms forward, 3.2 against 2.2 backward
// on the AVX-512 Xeon). = 1: one item per row, which Intel's CPU runtime vectorises 4x faster.
#ifndef ACTIVATION_ITEM_PER_ROW
#define ACTIVATION_ITEM_PER_ROW 0
#endif

// Per-value items: whether this item is a colour value's (its work-group is among the first ⌈3·rows / group size⌉)
// and, in *index, the flat index of that colour value or of its density (indices fit 32 bits: the host checks,
// ops/activations.cpp). The test is on the group id alone, so a work-group takes one branch.
inline int colour_value_item(uint n_rows, uint* index) {
  const uint group = (uint)get_local_size(0), colour_groups = (3 * n_rows + group - 1) / group;
  const int colour = get_group_id(0) < colour_groups;
  *index = (uint)get_global_id(0) - (colour ? 0 : colour_groups * group);
  return colour;
}

// density[i] = density_activation(raw_density[i]); rgb[i][c] = rgb_activation(raw_rgb[i][c]).
__kernel void activations_fwd(__global const float* raw_density, __global const float* raw_rgb,
                              __global float* density, __global float* rgb, const uint n_rows) {
#if ACTIVATION_ITEM_PER_ROW
  const size_t i = get_global_id(0);
  if (i >= n_rows) return;
  density[i] = density_activation(raw_density[i]);
  for (int c = 0; c < 3; ++c) rgb[3 * i + c] = rgb_activation(raw_rgb[3 * i + c]);
#else
  uint k;
  if (colour_value_item(n_rows, &k)) {
    if (k < 3 * n_rows) rgb[k] = rgb_activation(raw_rgb[k]);
  } else if (k < n_rows) {
    density[k] = density_activation(raw_density[k]);
  }
#endif
}

// Backward: the forward saves nothing beyond its inputs (the raw values), from which each derivative is
// recomputed. d_raw_density [rows], d_raw_rgb [rows][3]; items as in the forward.
__kernel void activations_bwd(__global const float* raw_density, __global const float* raw_rgb,
                              __global const float* d_density, __global const float* d_rgb,
                              __global float* d_raw_density, __global float* d_raw_rgb, const uint n_rows) {
#if ACTIVATION_ITEM_PER_ROW
  const size_t i = get_global_id(0);
  if (i >= n_rows) return;
  d_raw_density[i] = d_density[i] * density_activation_grad(raw_density[i]);
  for (int c = 0; c < 3; ++c) d_raw_rgb[3 * i + c] = d_rgb[3 * i + c] * rgb_activation_grad(raw_rgb[3 * i + c]);
#else
  uint k;
  if (colour_value_item(n_rows, &k)) {
    if (k < 3 * n_rows) d_raw_rgb[k] = d_rgb[k] * rgb_activation_grad(raw_rgb[k]);
  } else if (k < n_rows) {
    d_raw_density[k] = d_density[k] * density_activation_grad(raw_density[k]);
  }
#endif
}

#endif
