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

// Each function below is defined for float and for float16 (the per-vector items' explicit vectors), written once
// in a macro over the value type V as common.cl's exp_nonpositive is: the same operations lane by lane.
//
// stable_sigmoid(x) = 1/(1 + e^−x), evaluated through e = exp(−|x|) ≤ 1 so nothing overflows at |x| = 1e4 and the
// small side keeps its relative accuracy (e/(1 + e) instead of 1 − 1/(1 + e^|x|)).
// stable_sigmoid_grad(x) = sigmoid(x)·(1 − sigmoid(x)) = e/(1 + e)², e = exp(−|x|): even in x, finite everywhere, and
// accurate where 1 − sigmoid(x) would round to 0 (x > 17).
// stable_softplus(x) = log(1 + e^x) = max(x, 0) + log1p(e^−|x|): no overflow for large x (official uses
// jax.nn.softplus, which is computed the same way), no cancellation for very negative x.
// density_activation_grad: softplus' = sigmoid; relu' = 1 for x > 0 and 0 otherwise (0 at x = 0, as JAX's relu).
#if DENSITY_ACTIVATION == DENSITY_ACTIVATION_RELU
#define DENSITY_OF(V, x) fmax((x), 0.0f)
#define DENSITY_GRAD_OF(V, x) select((V)0.0f, (V)1.0f, (x) > 0.0f)
#else
#define DENSITY_OF(V, x) stable_softplus(x)
#define DENSITY_GRAD_OF(V, x) stable_sigmoid(x)
#endif
#define DEFINE_ACTIVATIONS(V)                                                                                      \
  ALWAYS_INLINE OVERLOADABLE V stable_sigmoid(V x) {                                                               \
    const V e = exp_nonpositive(-fabs(x));                                                                         \
    return x >= 0.0f ? 1.0f / (1.0f + e) : e / (1.0f + e);                                                         \
  }                                                                                                                \
  ALWAYS_INLINE OVERLOADABLE V stable_sigmoid_grad(V x) {                                                          \
    const V e = exp_nonpositive(-fabs(x));                                                                         \
    const V one_plus_e = 1.0f + e;                                                                                 \
    return e / (one_plus_e * one_plus_e);                                                                          \
  }                                                                                                                \
  ALWAYS_INLINE OVERLOADABLE V stable_softplus(V x) { return fmax(x, 0.0f) + log1p_unit(exp_nonpositive(-fabs(x))); } \
  ALWAYS_INLINE OVERLOADABLE V density_activation(V raw) { return DENSITY_OF(V, raw + DENSITY_BIAS); }             \
  ALWAYS_INLINE OVERLOADABLE V density_activation_grad(V raw) { return DENSITY_GRAD_OF(V, raw + DENSITY_BIAS); }   \
  ALWAYS_INLINE OVERLOADABLE V rgb_activation(V raw) {                                                             \
    return (1.0f + 2.0f * RGB_PADDING) * stable_sigmoid(raw) - RGB_PADDING;                                        \
  }                                                                                                                \
  ALWAYS_INLINE OVERLOADABLE V rgb_activation_grad(V raw) {                                                        \
    return (1.0f + 2.0f * RGB_PADDING) * stable_sigmoid_grad(raw);                                                 \
  }
DEFINE_ACTIVATIONS(float)
#if VECTOR_ITEMS
DEFINE_ACTIVATIONS(float16)
#endif

// The element-wise kernels' items (the host chooses per device, ops/activations.hpp), ACTIVATION_ITEMS:
//  - ACTIVATION_ITEMS_PER_VALUE: one item per value: the colour values' items first (flat index j of rgb), padded to
//    whole work-groups, then one item per density from the next work-group on. A row's three interleaved colour
//    values (stride 3) kept PoCL's vectoriser, which vectorises across work-items, from vectorising at all (17 ms
//    against 6 ms for 524,288 rows on its CPU device). A work-group holds only colour or only density items, decided
//    by its group id, which PoCL's loop over the group's items sees as invariant (3.4 against 2.3 ms forward when
//    items did a colour value and a density, masked, on the AVX-512 Xeon). GPUs read consecutive floats with
//    consecutive items.
//  - ACTIVATION_ITEMS_PER_ROW: one item per row, which Intel's CPU runtime vectorises 4x faster than the above.
//  - ACTIVATION_ITEMS_PER_VECTOR: one item per VECTOR_WIDTH (16) consecutive values, as a float16 (the last item of
//    each kind takes what is left one value at a time), the colour and density items split by work-group as per
//    value. PoCL runs each item's float16 code as it is, in full-width vector registers; its own vectorisation
//    across items of the per-value kernel ran 8 wide with long dependent chains (2.2 ms forward on the AVX-512
//    Xeon, against 0.8 ms for Intel's runtime per row).
#define ACTIVATION_ITEMS_PER_VALUE 0
#define ACTIVATION_ITEMS_PER_ROW 1
#define ACTIVATION_ITEMS_PER_VECTOR 2
#ifndef ACTIVATION_ITEMS
#define ACTIVATION_ITEMS ACTIVATION_ITEMS_PER_VALUE
#endif

// Per-value and per-vector items: whether this item is a colour item (its work-group is among the first
// ⌈colour_items / group size⌉) and, in *index, its index among the colour items or among the density items
// (indices fit 32 bits: the host checks, ops/activations.cpp). The test is on the group id alone, so a work-group
// takes one branch.
inline int colour_item(uint colour_items, uint* index) {
  const uint group = (uint)get_local_size(0), colour_groups = (colour_items + group - 1) / group;
  const int colour = get_group_id(0) < colour_groups;
  *index = (uint)get_global_id(0) - (colour ? 0 : colour_groups * group);
  return colour;
}

// The forward value of `raw` (backward: d·the derivative), by the colour or the density activation.
#define DEFINE_ACTIVATION_OF(V)                                                                  \
  ALWAYS_INLINE OVERLOADABLE V activation_of(V raw, V d, const int colour, const int backward) { \
    if (backward) return d * (colour ? rgb_activation_grad(raw) : density_activation_grad(raw)); \
    return colour ? rgb_activation(raw) : density_activation(raw);                               \
  }
DEFINE_ACTIVATION_OF(float)
#if VECTOR_ITEMS
DEFINE_ACTIVATION_OF(float16)
#endif

#if VECTOR_ITEMS
// Per-vector item v of n values: out = activation_of(raw, d) for values 16v .. 16v + 15, or those of them below n.
// `d` is read only when `backward`.
ALWAYS_INLINE void activate_vector_item(__global const float* raw, __global const float* d, __global float* out,
                                        uint v, uint n, const int colour, const int backward) {
  const uint first = v * VECTOR_WIDTH;
  if (first + VECTOR_WIDTH <= n) {
    const float16 d_values = backward ? vload16(v, d) : (float16)(0.0f);
    vstore16(activation_of(vload16(v, raw), d_values, colour, backward), v, out);
    return;
  }
  for (uint k = first; k < n; ++k) out[k] = activation_of(raw[k], backward ? d[k] : 0.0f, colour, backward);
}
#endif

// Forward (backward = 0): density[i] = density_activation(raw_density[i]), rgb[i][c] = rgb_activation(raw_rgb[i][c]).
// Backward: d_raw_density [rows], d_raw_rgb [rows][3], each derivative recomputed from the raw values (the forward
// saves nothing beyond its inputs). d_density and d_rgb are read only in the backward.
ALWAYS_INLINE void activations(__global const float* raw_density, __global const float* raw_rgb,
                               __global const float* d_density, __global const float* d_rgb, __global float* density,
                               __global float* rgb, const uint n_rows, const int backward) {
#if ACTIVATION_ITEMS == ACTIVATION_ITEMS_PER_ROW
  const size_t i = get_global_id(0);
  if (i >= n_rows) return;
  density[i] = activation_of(raw_density[i], backward ? d_density[i] : 0.0f, 0, backward);
  for (int c = 0; c < 3; ++c) rgb[3 * i + c] = activation_of(raw_rgb[3 * i + c], backward ? d_rgb[3 * i + c] : 0.0f, 1, backward);
#elif ACTIVATION_ITEMS == ACTIVATION_ITEMS_PER_VECTOR
  uint v;
  if (colour_item((3 * n_rows + VECTOR_WIDTH - 1) / VECTOR_WIDTH, &v)) {
    activate_vector_item(raw_rgb, d_rgb, rgb, v, 3 * n_rows, 1, backward);
  } else {
    activate_vector_item(raw_density, d_density, density, v, n_rows, 0, backward);
  }
#else
  uint k;
  if (colour_item(3 * n_rows, &k)) {
    if (k < 3 * n_rows) rgb[k] = activation_of(raw_rgb[k], backward ? d_rgb[k] : 0.0f, 1, backward);
  } else if (k < n_rows) {
    density[k] = activation_of(raw_density[k], backward ? d_density[k] : 0.0f, 0, backward);
  }
#endif
}

// density[i] = density_activation(raw_density[i]); rgb[i][c] = rgb_activation(raw_rgb[i][c]).
__kernel void activations_fwd(__global const float* raw_density, __global const float* raw_rgb,
                              __global float* density, __global float* rgb, const uint n_rows) {
  activations(raw_density, raw_rgb, 0, 0, density, rgb, n_rows, 0);
}

// Backward: d_raw_density [rows], d_raw_rgb [rows][3]; items as in the forward.
__kernel void activations_bwd(__global const float* raw_density, __global const float* raw_rgb,
                              __global const float* d_density, __global const float* d_rgb,
                              __global float* d_raw_density, __global float* d_raw_rgb, const uint n_rows) {
  activations(raw_density, raw_rgb, d_density, d_rgb, d_raw_density, d_raw_rgb, n_rows, 1);
}

#endif
