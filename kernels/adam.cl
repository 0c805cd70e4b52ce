// The optimiser over the MLP's flat parameter buffer: the gradient's global norm and non-finite count (for
// clipping and for skipping a bad step), and the Adam update (Kingma & Ba 2015, Algorithm 1, as flax's Adam
// in the official code: p −= lr · m̂ / (√v̂ + ε)).

// Strided partial sums over the flat gradient: slice p holds elements p, p + n_partials, p + 2·n_partials, …
// (neighbouring work-items read neighbouring floats). sumsq[p] = Σ g² over its finite elements;
// non_finite[p] = how many of its elements are NaN or ±Inf. The host adds the slices in double.
// 1-D launch over n_partials.
__kernel void grad_norm_partial(__global const float* grad, const uint n, __global float* sumsq,
                                __global uint* non_finite, const uint n_partials) {
  const uint p = get_global_id(0);
  if (p >= n_partials) return;
  float sum = 0.0f;
  uint bad = 0;
  for (uint i = p; i < n; i += n_partials) {
    const float g = grad[i];
    if (isfinite(g)) {
      sum += g * g;
    } else {
      ++bad;
    }
  }
  sumsq[p] = sum;
  non_finite[p] = bad;
}

// One Adam step on element i of the flat buffers. grad_scale multiplies the gradient first (global-norm
// clipping: min(1, max_norm / norm); 1 without clipping). inv_bias1 = 1 / (1 − β1^t), inv_bias2 =
// 1 / (1 − β2^t) for the 1-based step t, computed by the host in double. one_minus_beta1 and one_minus_beta2 are
// 1 − β computed by the host in double and then rounded: 1.0f − beta2 here would be 1 − float(0.999) =
// 0.00099998713, 1.3e-5 off the 0.001 the official code multiplies g² by (tests/official, adam.json). 1-D launch over n.
__kernel void adam_step(__global float* params, __global const float* grad, __global float* m, __global float* v,
                        const uint n, const float lr, const float beta1, const float beta2,
                        const float one_minus_beta1, const float one_minus_beta2, const float epsilon,
                        const float inv_bias1, const float inv_bias2, const float grad_scale) {
  const uint i = get_global_id(0);
  if (i >= n) return;
  const float g = grad[i] * grad_scale;
  const float m_new = beta1 * m[i] + one_minus_beta1 * g;
  // Guard: ((1 − β2)·g)·g, not (1 − β2)·g². g² overflows float32 for |g| > 1.8e19, while the term it feeds stays
  // representable up to |g| ≈ 5.8e20 (β2 = 0.999); the official flax Adam squares first (lax.square), stores
  // v = +∞ there, and from then on every update of that parameter is m̂/∞ = 0. The same two roundings either way.
  const float v_new = beta2 * v[i] + one_minus_beta2 * g * g;
  m[i] = m_new;
  v[i] = v_new;
  // Guard: √v̂ as √v·√(1/(1 − β2^t)), not √(v/(1 − β2^t)). v̂ = v·inv_bias2 overflows float32 for v > 3.4e35 at
  // step 1 (inv_bias2 = 1000) although √v̂ ≤ 1.9e19·31.6 is far inside the range; the official code divides
  // first (grad_sq_ema / (1 − β2^t)) and gets √∞ = ∞, an update of 0. m̂ = m·inv_bias1 ≤ max|g| cannot overflow.
  params[i] -= lr * (m_new * inv_bias1) / (sqrt(v_new) * sqrt(inv_bias2) + epsilon);
}
