// Host wrapper of kernels/adam.cl.
#include "ops/adam.hpp"

#include <string>

#include "core/error.hpp"
#include "cl/launch.hpp"
#include "ops/stage_checks.hpp"

namespace mipnerf::ops {

AdamKernels::AdamKernels(ocl::Context& ctx) : ctx_(&ctx) {
  auto& program = ctx.program({"common.cl", "adam.cl"});
  grad_norm_partial_ = &program.kernel("grad_norm_partial");
  adam_step_ = &program.kernel("adam_step");
}

void AdamKernels::grad_norm_partial(const ocl::DeviceArray<float>& grad, size_t n, ocl::DeviceArray<float>& sumsq,
                                    ocl::DeviceArray<cl_uint>& non_finite, size_t n_partials) {
  const std::string where = "grad_norm_partial";
  if (n_partials == 0) throw Error(where + ": n_partials must be positive");
  grad.require_size(n, where);
  sumsq.require_size(n_partials, where);
  non_finite.require_size(n_partials, where);
  ocl::set_args(*grad_norm_partial_, where, grad, detail::to_uint(n, where, "n"), sumsq, non_finite,
                detail::to_uint(n_partials, where, "n_partials"));
  ocl::launch_1d(*ctx_, *grad_norm_partial_, n_partials, where);
}

void AdamKernels::adam_step(ocl::DeviceArray<float>& params, const ocl::DeviceArray<float>& grad,
                            ocl::DeviceArray<float>& m, ocl::DeviceArray<float>& v, size_t n,
                            const AdamStepArgs& a) {
  const std::string where = "adam_step";
  params.require_size(n, where);
  grad.require_size(n, where);
  m.require_size(n, where);
  v.require_size(n, where);
  ocl::set_args(*adam_step_, where, params, grad, m, v, detail::to_uint(n, where, "n"), a.lr, a.beta1, a.beta2,
                a.one_minus_beta1, a.one_minus_beta2, a.epsilon, a.inv_bias1, a.inv_bias2, a.grad_scale);
  ocl::launch_1d(*ctx_, *adam_step_, n, where);
}

}  // namespace mipnerf::ops
