// CPU reference (double) of kernels/interlevel.cl, same names: Zip-NeRF's anti-aliased interlevel loss (camp_zipnerf
// loss_utils.spline_interlevel_loss, stepfun.blur_and_resample_weights), the forward per ray and the gradient w.r.t.
// the proposal weights (the NeRF's histogram is stop-gradient, as in the official).
#pragma once

#include <cstddef>
#include <vector>

namespace mipnerf::ref {

// float32's epsilon, the official loss's ε (jnp.finfo(jnp.float32).eps).
constexpr double kInterlevelEps = 1.1920928955078125e-07;

// One ray: w_blur [M] = the histogram (c [N+1], w [N]) as a pdf, blurred by a box of half-width r, integrated over
// each of the intervals of cp [M+1] (stepfun.blur_and_resample_weights(cp, c, w, r)). The same
// event walk as the kernel, in double; the ramps' ends are c ± r with blur_stepfun's plus_eps floor (the next float32
// above c).
void blur_and_resample_weights(const double* c, const double* w, size_t n_intervals, const double* cp,
                               size_t n_proposal, double halfwidth, double* w_blur);

// What float32 rounding can move each w_blur_j by (for the kernel tests' bounds), from the same walk with absolute
// values: area_abs [M] = ∫_{cp_j}^{cp_{j+1}} (|P_trail| + Σ_active (|P_{k+1}| + |P_k|) · ramp_k), events [M] = the
// knots inside interval j, active [M] = the most ramps under way at once in it, ramp_jumps [M] = Σ (|P_{k+1}| + |P_k|)
// · (the fraction of ramp [c_k − r, c_k + r], widened by a float32 knot's rounding, that overlaps interval j).
struct BlurMagnitudes {
  std::vector<double> area_abs, events, active, ramp_jumps;
};
BlurMagnitudes blur_and_resample_magnitudes(const double* c, const double* w, size_t n_intervals, const double* cp,
                                            size_t n_proposal, double halfwidth);

// For the kernel tests: per element of one ray's w_blur [M], what float32 can move it by (kernels/interlevel.cl's
// walk): p̃ is a sum of the active ramps and a level, ~6 roundings each (two levels' divisions, the jump, the fraction's
// subtraction and division, the product), trapezoids add two more and are summed over the interval's events; and each
// knot c ± r is rounded by u (|c| + r), which moves its ramp's area by that times its levels.
std::vector<double> blur_and_resample_float32_bound(const double* c, const double* w, size_t n_intervals,
                                                    const double* cp, size_t n_proposal, double halfwidth);

// max(0, w_blur − wp)² / (wp + ε) (one interval: the truncated chi-square of loss_utils.spline_interlevel_loss).
double interlevel_interval_loss(double w_blur, double wp);

// Mirrors spline_interlevel_fwd over R rays: c [R][N+1], w [R][N], cp [R][M+1], wp [R][M] → w_blur [R][M] and
// ray_loss [R] = Σ_j interlevel_interval_loss(w_blur_j, wp_j). The loss is mult · Σ ray_loss / (R·M).
void spline_interlevel_fwd(const double* c, const double* w, const double* cp, const double* wp, double halfwidth,
                           double* w_blur, double* ray_loss, size_t n_rays, size_t n_intervals, size_t n_proposal);

// Mirrors spline_interlevel_bwd over n_values = R·M: d_wp = grad_scale · ∂ interval loss / ∂wp.
void spline_interlevel_bwd(const double* w_blur, const double* wp, double grad_scale, double* d_wp, size_t n_values);

// The official loss of one round: mult · mean over the R·M intervals (loss_utils.spline_interlevel_loss).
double spline_interlevel_loss(const std::vector<double>& ray_loss, size_t n_proposal, double mult);

}  // namespace mipnerf::ref
