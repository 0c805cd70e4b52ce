// Host wrapper of kernels/contract.cl: mip-NeRF 360's contraction of Gaussians (μ' = contract(μ), Σ' = J Σ Jᵀ, the
// official coord.contract through coord.track_linearize) forward and backward, and the ray warps of
// coord.construct_ray_warps with fn = reciprocal (configs/360.gin's raydist_fn). Standalone stages: the training graph
// runs the contraction's forward inside contracted_ipe.cl and the warp inside sample_intervals.cl.
#pragma once

#include <cstddef>

#include "cl/buffer.hpp"
#include "cl/context.hpp"

namespace mipnerf::ops {

// Gaussians with full symmetric covariances, [rows][3] each: means (world), covs = the diagonal (xx, yy, zz) and
// cov_off = (xy, xz, yz). A diagonal covariance is cov_off = 0.
struct GaussianRows {
  const ocl::DeviceArray<float>& means;
  const ocl::DeviceArray<float>& covs;
  const ocl::DeviceArray<float>& cov_off;
  size_t n_rows;
};

// Written rows, [rows][3] each (overwritten): the contracted Gaussians, or the gradients w.r.t. the inputs.
struct GaussianRowsOut {
  ocl::DeviceArray<float>& means;
  ocl::DeviceArray<float>& covs;
  ocl::DeviceArray<float>& cov_off;
};

class ContractGaussians {
 public:
  explicit ContractGaussians(ocl::Context& ctx);

  // Enqueues contract_gaussians_fwd: `out` = the contracted Gaussians (inside the unit ball, the inputs).
  void fwd(const GaussianRows& in, const GaussianRowsOut& out);
  // Enqueues contract_gaussians_bwd: `d_in` = ∂L/∂(means, covs, cov_off) from `d_out` = ∂L/∂ of fwd's outputs (same
  // layouts; cov_off's gradient is w.r.t. the one stored number of each pair of entries).
  void bwd(const GaussianRows& in, const GaussianRows& d_out, const GaussianRowsOut& d_in);

 private:
  ocl::Context* ctx_;
  ::cl::Kernel* fwd_;
  ::cl::Kernel* bwd_;
};

// The reciprocal ray warp between near and far: s = (1/t − 1/near)/(1/far − 1/near), t = 1/(s/far + (1 − s)/near).
// near must be finite and > 0 (the official's 1/near is ∞ at near = 0 and its warps are NaN: refused here), far >
// near, and far may be +∞ (s = 1 − near/t).
class RayWarp {
 public:
  RayWarp(ocl::Context& ctx, float near, float far);
  float near() const { return near_; }
  float far() const { return far_; }

  // Enqueues ray_warp_t_to_s: s [n] from t [n].
  void t_to_s(const ocl::DeviceArray<float>& t, ocl::DeviceArray<float>& s, size_t n);
  // Enqueues ray_warp_s_to_t: t [n] and dt_ds [n] (dt/ds = t² (1/near − 1/far)) from s [n].
  void s_to_t(const ocl::DeviceArray<float>& s, ocl::DeviceArray<float>& t, ocl::DeviceArray<float>& dt_ds, size_t n);

 private:
  ocl::Context* ctx_;
  float near_, far_;
  ::cl::Kernel* t_to_s_;
  ::cl::Kernel* s_to_t_;
};

}  // namespace mipnerf::ops
