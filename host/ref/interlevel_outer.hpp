// CPU reference (double) of kernels/interlevel_outer.cl, same names: mip-NeRF 360's interlevel loss (multinerf
// stepfun.lossfun_outer through train_utils.interlevel_loss), the forward per ray and the gradient w.r.t. the proposal
// weights (the NeRF's histogram is stop-gradient, as in the official). Written as the official writes it: the outer
// measure as the difference of two cumulative sums at stepfun.searchsorted's indices (the kernel sums each window
// directly), so the two are independent.
#pragma once

#include <cstddef>
#include <vector>

namespace mipnerf::ref {

// stepfun.searchsorted(a, v) for one query: lo = the last k with a_k ≤ v (0 when none), hi = the first k with
// a_k > v (the last index when none). `a` has `count` sorted entries.
void outer_searchsorted(const double* a, size_t count, double v, size_t* lo, size_t* hi);

// One ray's outer measure of (cp [M+1], wp [M]) on the NeRF's intervals c [N+1]: bound [N] (stepfun.inner_outer's
// second output).
void outer_bounds(const double* c, size_t n_intervals, const double* cp, const double* wp, size_t n_proposal,
                  double* bound);

// max(0, w − bound)² / (w + ε), ε = float32's epsilon (stepfun.lossfun_outer for one interval).
double outer_interval_loss(double w, double bound);

// Mirrors outer_interlevel_fwd over R rays: ray_loss [R] = Σ_j outer_interval_loss(w_j, bound_j).
void outer_interlevel_fwd(const double* c, const double* w, const double* cp, const double* wp, double* ray_loss,
                          size_t n_rays, size_t n_intervals, size_t n_proposal);

// Mirrors outer_interlevel_bwd: d_wp [R][M] = grad_scale · ∂(Σ_j interval loss)/∂wp.
void outer_interlevel_bwd(const double* c, const double* w, const double* cp, const double* wp, double grad_scale,
                          double* d_wp, size_t n_rays, size_t n_intervals, size_t n_proposal);

// The official loss of one round: mult · mean over the R·N NeRF intervals (train_utils.interlevel_loss).
double outer_interlevel_loss(const std::vector<double>& ray_loss, size_t n_intervals, double mult);

}  // namespace mipnerf::ref
