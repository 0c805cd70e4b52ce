// Host wrapper of kernels/resample.cl.
#include "ops/resample.hpp"

#include <algorithm>

#include "cl/launch.hpp"
#include "ops/stage_checks.hpp"
#include "ops/vector_items.hpp"

namespace mipnerf::ops {

Resample::Resample(ocl::Context& ctx, ResampleItems items)
    : ctx_(&ctx), items_(items_for_device(ctx, items, ResampleItems::per_vector, ResampleItems::per_ray)) {
  const auto options =
      ocl::BuildOptions().define("RESAMPLE_RAYS_PER_VECTOR", items_ == ResampleItems::per_vector ? 1 : 0);
  fwd_ = &ctx.program({"common.cl", "resample.cl"}, options).kernel("resample_fwd");
}

void Resample::fwd(const ResampleOptions& options, const ResampleInputs& in, ocl::DeviceArray<float>& t_new,
                   const RngKey& key) {
  const std::string where = "resample_fwd";
  if (in.n_samples == 0) throw Error(where + ": n_samples must be at least 1");
  if (in.new_samples == 0) {
    throw Error(where +
                ": new_samples (intervals to draw) must be at least 1; mip-NeRF draws as many as the previous "
                "level has (n_samples)");
  }
  if (!(options.padding >= 0.0f)) throw Error(where + ": padding must be ≥ 0, got " + std::to_string(options.padding));
  detail::require(in.t_edges, in.n_rays * (in.n_samples + 1), where);
  detail::require(in.weights, in.n_rays * in.n_samples, where);
  detail::require(t_new, in.n_rays * (in.new_samples + 1), where);
  ocl::set_args(*fwd_, where, in.t_edges, in.weights, t_new, detail::to_uint(in.n_rays, where, "rays"),
                detail::to_uint(in.n_samples, where, "samples"), detail::to_uint(in.new_samples, where, "new samples"),
                options.padding, static_cast<cl_uint>(options.blur ? 1 : 0),
                static_cast<cl_uint>(options.randomized ? 1 : 0), static_cast<cl_ulong>(key.seed),
                static_cast<cl_uint>(key.step), static_cast<cl_uint>(key.first_ray));
  if (items_ == ResampleItems::per_vector) {
    detail::to_uint(in.n_rays * (std::max(in.n_samples, in.new_samples) + 1), where, "edges");  // 32-bit lane indices
    return ocl::launch_1d(*ctx_, *fwd_, (in.n_rays + kVectorWidth - 1) / kVectorWidth, where);
  }
  ocl::launch_1d(*ctx_, *fwd_, in.n_rays, where);
}

}  // namespace mipnerf::ops
