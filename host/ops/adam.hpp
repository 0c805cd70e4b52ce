// Host wrapper of kernels/adam.cl: the gradient-norm partial sums and the Adam update over flat buffers.
// Each kernel's arguments are set here, once.
#pragma once

#include <cstddef>

#include "cl/buffer.hpp"
#include "cl/context.hpp"

namespace mipnerf::ops {

// The per-step scalars of adam_step, grouped (they are set as kernel arguments in one place).
struct AdamStepArgs {
  float lr = 0.0f;                 // learning rate of this step
  float beta1 = 0.9f;              // first-moment decay
  float beta2 = 0.999f;            // second-moment decay
  float one_minus_beta1 = 0.1f;    // 1 − β1, computed in double and rounded (not 1.0f − beta1)
  float one_minus_beta2 = 0.001f;  // 1 − β2, likewise: 1.0f − 0.999f would be 1.3e-5 off 0.001
  float epsilon = 1e-8f;           // added to √v̂
  float inv_bias1 = 1.0f;          // 1 / (1 − β1^t)
  float inv_bias2 = 1.0f;          // 1 / (1 − β2^t)
  float grad_scale = 1.0f;         // multiplies the gradient (clipping); 1 = none
};

class AdamKernels {
 public:
  explicit AdamKernels(ocl::Context& ctx);

  // grad_norm_partial: sumsq[p], non_finite[p] for p < n_partials over grad[0 … n).
  void grad_norm_partial(const ocl::DeviceArray<float>& grad, size_t n, ocl::DeviceArray<float>& sumsq,
                         ocl::DeviceArray<cl_uint>& non_finite, size_t n_partials);

  // adam_step over elements 0 … n − 1 of params, grad, m, v.
  void adam_step(ocl::DeviceArray<float>& params, const ocl::DeviceArray<float>& grad, ocl::DeviceArray<float>& m,
                 ocl::DeviceArray<float>& v, size_t n, const AdamStepArgs& args);

 private:
  ocl::Context* ctx_;
  ::cl::Kernel* grad_norm_partial_;
  ::cl::Kernel* adam_step_;
};

}  // namespace mipnerf::ops
