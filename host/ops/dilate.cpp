// Host wrapper of kernels/dilate.cl.
#include "ops/dilate.hpp"

#include <cmath>

#include "cl/launch.hpp"
#include "core/error.hpp"
#include "ops/stage_checks.hpp"

namespace mipnerf::ops {

MaxDilate::MaxDilate(ocl::Context& ctx) : ctx_(&ctx) {
  fwd_ = &ctx.program({"dilate.cl"}).kernel("max_dilate_weights_fwd");
}

void MaxDilate::fwd(const ocl::DeviceArray<float>& s_edges, const ocl::DeviceArray<float>& weights, size_t n_rays,
                    size_t n_intervals, float dilation, ocl::DeviceArray<float>& s_out,
                    ocl::DeviceArray<float>& w_out, ocl::DeviceArray<uint32_t>& scratch) {
  const std::string where = "max_dilate_weights_fwd";
  if (n_intervals == 0) throw Error(where + ": a histogram of 0 intervals; it needs at least one");
  if (!(dilation >= 0.0f) || !std::isfinite(dilation)) {
    throw Error(where + ": dilation " + std::to_string(dilation) + "; it must be finite and >= 0");
  }
  detail::require(s_edges, n_rays * (n_intervals + 1), where);
  detail::require(weights, n_rays * n_intervals, where);
  detail::require(s_out, n_rays * dilated_edges(n_intervals), where);
  detail::require(w_out, n_rays * dilated_intervals(n_intervals), where);
  detail::require(scratch, n_rays * n_intervals, where);
  detail::to_uint(n_rays * dilated_edges(n_intervals), where, "dilated edges");
  if (n_rays == 0) return;
  ocl::set_args(*fwd_, where, s_edges, weights, dilation, 0.0f, 1.0f, s_out, w_out, scratch,
                static_cast<cl_uint>(n_rays), static_cast<cl_uint>(n_intervals));
  ocl::launch_1d(*ctx_, *fwd_, n_rays, where);
}

}  // namespace mipnerf::ops
