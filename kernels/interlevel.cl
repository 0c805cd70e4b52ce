// Zip-NeRF's anti-aliased ("spline") interlevel loss (Barron et al. 2023, section "Z-Aliasing and Proposal
// Supervision"; the official camp_zipnerf loss_utils.spline_interlevel_loss with stepfun.blur_and_resample_weights),
// forward and backward.
//
// Per ray: the NeRF's final histogram (c, w) over N intervals and one proposal round's histogram (cp, wp) over M.
//   p_i      = w_i / (c_{i+1} − c_i)                          the step pdf (stepfun.weight_to_pdf; 0 on an interval
//                                                              narrower than FLT_MIN, clipped to FLT_MAX, as safe_div)
//   p̃(x)     = (1 / 2r) ∫_{x−r}^{x+r} p                        the pdf blurred by a box of half-width r (linspline
//                                                              .blur_stepfun: a linear spline, knots c_k ± r)
//   w_blur_j = max(0, ∫_{cp_j}^{cp_{j+1}} p̃)                   resampled into the proposal's intervals
//   loss     = mult · mean_{rays, j} max(0, w_blur_j − wp_j)² / (wp_j + ε),  ε = FLT_EPSILON
// (c, w) carry no gradient (the official stop_gradient onto the NeRF): the backward is ∂loss/∂wp only.
//
// How p̃ is evaluated. Writing p̃ as a sum of ramps: with the zero-padded levels P_0 = 0, P_k = p_{k−1}, P_{N+1} = 0
// and the jumps J_k = P_{k+1} − P_k (k = 0..N), the box turns the jump at c_k into a ramp from lo_k = c_k − r to
// hi_k = c_k + r, so
//   p̃(x) = P_trail + Σ_{k = trail}^{lead − 1} J_k · (x − lo_k) / (hi_k − lo_k)
// where lead = #{k : lo_k ≤ x} and trail = #{k : hi_k ≤ x}: the finished ramps telescope to the level P_trail, read
// directly rather than summed, so no rounding drifts along the ray (the official cumulative sums of slopes do drift in
// float32). With a constant r both lo and hi are sorted, so the spline's knots are a merge of two sorted lists (no sort,
// unlike blur_stepfun's argsort) and the queries cp are a third sorted list: one walk over the three visits every
// knot and query in order, and between two consecutive events p̃ is linear, so the trapezoid rule integrates it
// exactly. Each w_blur_j is the sum of the trapezoids between cp_j and cp_{j+1} only (linspline.compute_integral and
// interpolate_integral difference a global integral instead; summing only the interval's own non-negative areas keeps
// small weights accurate where the difference of two large integrals would cancel).
// hi_k = max(c_k + r, nextafter(c_k)) as blur_stepfun's plus_eps: every ramp has a positive width, so r may be tiny.
// Reference: host/ref/interlevel.hpp (same names).

// The level P_k of the zero-padded step pdf (k = 0..N+1): stepfun.weight_to_pdf's guards, so a zero-width interval
// (or one narrower than FLT_MIN) carries no density and its weight is dropped, as the official drops it.
inline float interlevel_pdf_level(__global const float* c, __global const float* w, uint k, uint n_intervals) {
  if (k == 0 || k > n_intervals) return 0.0f;
  const float width = c[k] - c[k - 1];
  return width < FLT_MIN ? 0.0f : fmin(w[k - 1] / width, FLT_MAX);
}

// The ramp of knot k: starts at c_k − r, ends at max(c_k + r, the next float above c_k) (blur_stepfun's plus_eps,
// FLT_MIN for |c_k| < FLT_MIN), so its width is positive whatever r is.
inline float interlevel_ramp_start(float c_k, float halfwidth) { return c_k - halfwidth; }
inline float interlevel_ramp_end(float c_k, float halfwidth) {
  const float above = fabs(c_k) < FLT_MIN ? FLT_MIN : nextafter(c_k, INFINITY);
  return fmax(c_k + halfwidth, above);
}

// p̃(x) with the ramps trail..lead−1 under way. Clamped at 0: p̃ is an average of a non-negative pdf, and only
// rounding of the ramps' partial sums could make it negative.
inline float interlevel_blurred_pdf(__global const float* c, __global const float* w, uint n_intervals,
                                    float halfwidth, uint trail, uint lead, float x) {
  float y = interlevel_pdf_level(c, w, trail, n_intervals);
  for (uint k = trail; k < lead; ++k) {
    const float lo = interlevel_ramp_start(c[k], halfwidth), hi = interlevel_ramp_end(c[k], halfwidth);
    const float jump = interlevel_pdf_level(c, w, k + 1, n_intervals) - interlevel_pdf_level(c, w, k, n_intervals);
    y += jump * clamp((x - lo) / (hi - lo), 0.0f, 1.0f);
  }
  return fmax(y, 0.0f);
}

// One ray: w_blur [M] = (c, w) blurred by r and resampled into cp [M+1] (stepfun.blur_and_resample_weights).
// Every step advances one of the three lists (lo knots, hi knots, queries), so the walk ends after at most
// 2(N+1) + M+1 steps even for NaN inputs. Ties: a lo knot before a query, a query before a hi knot; p̃ is continuous,
// so the order of tied events changes no value.
inline void blur_and_resample_weights(__global const float* c, __global const float* w, uint n_intervals,
                                      __global const float* cp, uint n_proposal, float halfwidth,
                                      __global float* w_blur) {
  uint lead = 0, trail = 0, query = 0;
  float x_prev = fmin(interlevel_ramp_start(c[0], halfwidth), cp[0]), y_prev = 0.0f, area = 0.0f;
  while (query <= n_proposal) {
    int event = 2;  // 0: a ramp starts (lo), 1: a ramp ends (hi), 2: a query
    float x = cp[query];
    const float x_lo = lead <= n_intervals ? interlevel_ramp_start(c[lead], halfwidth) : INFINITY;
    if (lead <= n_intervals && x_lo <= x) {
      event = 0;
      x = x_lo;
    }
    if (trail < lead) {
      const float x_hi = interlevel_ramp_end(c[trail], halfwidth);
      if (x_hi < x) {
        event = 1;
        x = x_hi;
      }
    }
    const float y = interlevel_blurred_pdf(c, w, n_intervals, halfwidth, trail, lead, x);
    area += (x - x_prev) * 0.5f * (y_prev + y);
    x_prev = x;
    y_prev = y;
    if (event == 0) {
      ++lead;
    } else if (event == 1) {
      ++trail;
    } else {
      if (query > 0) w_blur[query - 1] = fmax(area, 0.0f);
      area = 0.0f;
      ++query;
    }
  }
}

// The loss of one proposal interval before the mean: max(0, w_blur − wp)² / (wp + ε), mip-NeRF 360's truncated
// chi-square interlevel loss applied to the blurred weights. ε keeps wp = 0 finite: there the loss is w_blur² / ε,
// large on purpose (the proposal must not miss mass the NeRF sees).
inline float interlevel_interval_loss(float w_blur, float wp) {
  const float excess = fmax(0.0f, w_blur - wp);
  return excess * excess / (wp + FLT_EPSILON);
}

// One work-item per ray.
//   c [R][N+1], w [R][N]     the NeRF's final histogram (normalised s-distances, weights)
//   cp [R][M+1], wp [R][M]   one proposal round's histogram
//   halfwidth                r, the round's blur (the official blurs (0.03, 0.003) per round), > 0
//   w_blur [R][M]            out: the blurred, resampled NeRF weights (the backward reads them)
//   ray_loss [R]             out: Σ_j max(0, w_blur_j − wp_j)² / (wp_j + ε); the loss is mult · Σ_rays / (R·M)
__kernel void spline_interlevel_fwd(__global const float* c, __global const float* w, __global const float* cp,
                                    __global const float* wp, const float halfwidth, __global float* w_blur,
                                    __global float* ray_loss, const uint n_rays, const uint n_intervals,
                                    const uint n_proposal) {
  const uint ray = get_global_id(0);
  if (ray >= n_rays) return;
  __global const float* ray_c = c + (size_t)ray * (n_intervals + 1);
  __global const float* ray_w = w + (size_t)ray * n_intervals;
  __global const float* ray_cp = cp + (size_t)ray * (n_proposal + 1);
  __global const float* ray_wp = wp + (size_t)ray * n_proposal;
  __global float* ray_w_blur = w_blur + (size_t)ray * n_proposal;
  blur_and_resample_weights(ray_c, ray_w, n_intervals, ray_cp, n_proposal, halfwidth, ray_w_blur);
  float sum = 0.0f;
  for (uint j = 0; j < n_proposal; ++j) sum += interlevel_interval_loss(ray_w_blur[j], ray_wp[j]);
  ray_loss[ray] = sum;
}

// One work-item per proposal interval (ray · M + j):
//   d_wp = grad_scale · ∂/∂wp [max(0, w_blur − wp)² / (wp + ε)]
//        = −grad_scale · (2e / (wp + ε) + e² / (wp + ε)²),  e = max(0, w_blur − wp)  (0 where wp ≥ w_blur)
// grad_scale = mult / (R·M) for the whole batch (times the upstream gradient), w_blur from spline_interlevel_fwd.
__kernel void spline_interlevel_bwd(__global const float* w_blur, __global const float* wp, const float grad_scale,
                                    __global float* d_wp, const uint n_values) {
  const uint i = get_global_id(0);
  if (i >= n_values) return;
  const float excess = fmax(0.0f, w_blur[i] - wp[i]);
  const float ratio = excess / (wp[i] + FLT_EPSILON);
  d_wp[i] = -grad_scale * ratio * (2.0f + ratio);
}
