// CPU reference (double) of kernels/distortion.cl, same names: mip-NeRF 360's distortion loss (eq. 15; camp_zipnerf
// stepfun.lossfun_distortion), its O(N) form as the kernel computes it, and the quadratic double sum as an independent
// check.
#pragma once

#include <cstddef>
#include <vector>

namespace mipnerf::ref {

// Mirrors distortion_fwd: ray_loss [R] = Σ_{i,j} w_i w_j |u_i − u_j| + (1/3) Σ_i w_i² (t_{i+1} − t_i) for t [R][N+1]
// (sorted), w [R][N], u the midpoints; by the O(N) recurrences of the kernel.
void distortion_fwd(const double* t, const double* w, double* ray_loss, size_t n_rays, size_t n_intervals);

// Mirrors distortion_bwd: d_w [R][N] = grad_scale · ∂L/∂w, d_t [R][N+1] = grad_scale · ∂L/∂t.
void distortion_bwd(const double* t, const double* w, double grad_scale, double* d_w, double* d_t, size_t n_rays,
                    size_t n_intervals);

// Eq. 15 for one ray as written, the O(N²) double sum (stepfun.lossfun_distortion's quadratic form): the oracle the
// O(N) forms are checked against.
double distortion_quadratic(const double* t, const double* w, size_t n_intervals);

// The official loss: mult · mean over the rays (loss_utils.distortion_loss).
double distortion_loss(const std::vector<double>& ray_loss, double mult);

}  // namespace mipnerf::ref
