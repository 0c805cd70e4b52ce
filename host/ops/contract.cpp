// Host wrapper of kernels/contract.cl.
#include "ops/contract.hpp"

#include <cmath>
#include <sstream>

#include "cl/launch.hpp"
#include "core/error.hpp"
#include "ops/stage_checks.hpp"

namespace mipnerf::ops {

namespace {
void require_rows(const GaussianRows& rows, size_t n_rows, const std::string& where) {
  detail::require(rows.means, 3 * n_rows, where);
  detail::require(rows.covs, 3 * n_rows, where);
  detail::require(rows.cov_off, 3 * n_rows, where);
}

void require_rows(const GaussianRowsOut& rows, size_t n_rows, const std::string& where) {
  detail::require(rows.means, 3 * n_rows, where);
  detail::require(rows.covs, 3 * n_rows, where);
  detail::require(rows.cov_off, 3 * n_rows, where);
}
}  // namespace

ContractGaussians::ContractGaussians(ocl::Context& ctx) : ctx_(&ctx) {
  auto& program = ctx.program({"common.cl", "contract.cl"});
  fwd_ = &program.kernel("contract_gaussians_fwd");
  bwd_ = &program.kernel("contract_gaussians_bwd");
}

void ContractGaussians::fwd(const GaussianRows& in, const GaussianRowsOut& out) {
  const std::string where = "contract_gaussians_fwd";
  require_rows(in, in.n_rows, where);
  require_rows(out, in.n_rows, where);
  const cl_uint rows = detail::to_uint(in.n_rows, where, "rows");
  if (rows == 0) return;
  ocl::set_args(*fwd_, where, in.means, in.covs, in.cov_off, out.means, out.covs, out.cov_off, rows);
  ocl::launch_1d(*ctx_, *fwd_, rows, where);
}

void ContractGaussians::bwd(const GaussianRows& in, const GaussianRows& d_out, const GaussianRowsOut& d_in) {
  const std::string where = "contract_gaussians_bwd";
  if (d_out.n_rows != in.n_rows) {
    throw Error(where + ": the gradients hold " + std::to_string(d_out.n_rows) + " rows but the Gaussians " +
                std::to_string(in.n_rows) + "; pass the forward's rows");
  }
  require_rows(in, in.n_rows, where);
  require_rows(d_out, in.n_rows, where);
  require_rows(d_in, in.n_rows, where);
  const cl_uint rows = detail::to_uint(in.n_rows, where, "rows");
  if (rows == 0) return;
  ocl::set_args(*bwd_, where, in.means, in.covs, in.cov_off, d_out.means, d_out.covs, d_out.cov_off, d_in.means,
                d_in.covs, d_in.cov_off, rows);
  ocl::launch_1d(*ctx_, *bwd_, rows, where);
}

RayWarp::RayWarp(ocl::Context& ctx, float near, float far) : ctx_(&ctx), near_(near), far_(far) {
  if (!(near > 0.0f) || !std::isfinite(near)) {
    std::ostringstream message;
    message << "ray warp: near = " << near
            << " cannot be warped by 1/t (the official construct_ray_warps gives NaN for near = 0); "
               "set a near bound > 0";
    throw Error(message.str());
  }
  if (!(far > near)) {
    std::ostringstream message;
    message << "ray warp: far = " << far << " is not beyond near = " << near << "; set far > near (inf allowed)";
    throw Error(message.str());
  }
  auto& program = ctx.program({"common.cl", "contract.cl"});
  t_to_s_ = &program.kernel("ray_warp_t_to_s");
  s_to_t_ = &program.kernel("ray_warp_s_to_t");
}

void RayWarp::t_to_s(const ocl::DeviceArray<float>& t, ocl::DeviceArray<float>& s, size_t n) {
  const std::string where = "ray_warp_t_to_s";
  detail::require(t, n, where);
  detail::require(s, n, where);
  const cl_uint count = detail::to_uint(n, where, "distances");
  if (count == 0) return;
  ocl::set_args(*t_to_s_, where, t, s, near_, far_, count);
  ocl::launch_1d(*ctx_, *t_to_s_, count, where);
}

void RayWarp::s_to_t(const ocl::DeviceArray<float>& s, ocl::DeviceArray<float>& t, ocl::DeviceArray<float>& dt_ds,
                     size_t n) {
  const std::string where = "ray_warp_s_to_t";
  detail::require(s, n, where);
  detail::require(t, n, where);
  detail::require(dt_ds, n, where);
  const cl_uint count = detail::to_uint(n, where, "normalised distances");
  if (count == 0) return;
  ocl::set_args(*s_to_t_, where, s, t, dt_ds, near_, far_, count);
  ocl::launch_1d(*ctx_, *s_to_t_, count, where);
}

}  // namespace mipnerf::ops
