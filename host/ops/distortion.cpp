// Host wrapper of kernels/distortion.cl.
#include "ops/distortion.hpp"

#include "cl/launch.hpp"
#include "core/error.hpp"
#include "ops/stage_checks.hpp"

namespace mipnerf::ops {

double distortion_loss_value(const std::vector<float>& ray_loss, size_t batch_rays, float mult) {
  if (batch_rays == 0) throw Error("distortion loss: a batch without rays");
  double sum = 0.0;
  for (float v : ray_loss) sum += v;
  return static_cast<double>(mult) * sum / static_cast<double>(batch_rays);
}

Distortion::Distortion(ocl::Context& ctx) : ctx_(&ctx) {
  auto& program = ctx.program({"distortion.cl"});
  fwd_ = &program.kernel("distortion_fwd");
  bwd_ = &program.kernel("distortion_bwd");
}

void Distortion::check(const DistortionInputs& in, const std::string& where) const {
  if (in.n_intervals == 0) throw Error(where + ": a histogram without intervals (N = 0)");
  detail::require(in.t, in.n_rays * (in.n_intervals + 1), where);
  detail::require(in.w, in.n_rays * in.n_intervals, where);
  detail::to_uint(in.n_rays * (in.n_intervals + 1), where, "edges");
}

void Distortion::fwd(const DistortionInputs& in, ocl::DeviceArray<float>& ray_loss) {
  const std::string where = "distortion_fwd";
  check(in, where);
  detail::require(ray_loss, in.n_rays, where);
  if (in.n_rays == 0) return;
  ocl::set_args(*fwd_, where, in.t, in.w, ray_loss, static_cast<cl_uint>(in.n_rays),
                static_cast<cl_uint>(in.n_intervals));
  ocl::launch_1d(*ctx_, *fwd_, in.n_rays, where);
}

void Distortion::bwd(const DistortionInputs& in, float mult, size_t batch_rays, ocl::DeviceArray<float>& d_w,
                     ocl::DeviceArray<float>& d_t, float upstream) {
  const std::string where = "distortion_bwd";
  check(in, where);
  if (batch_rays < in.n_rays) {
    throw Error(where + ": a batch of " + std::to_string(batch_rays) + " rays cannot hold a chunk of " +
                std::to_string(in.n_rays));
  }
  detail::require(d_w, in.n_rays * in.n_intervals, where);
  detail::require(d_t, in.n_rays * (in.n_intervals + 1), where);
  if (in.n_rays == 0) return;
  const float scale = static_cast<float>(static_cast<double>(upstream) * mult / static_cast<double>(batch_rays));
  ocl::set_args(*bwd_, where, in.t, in.w, scale, d_w, d_t, static_cast<cl_uint>(in.n_rays),
                static_cast<cl_uint>(in.n_intervals));
  ocl::launch_1d(*ctx_, *bwd_, in.n_rays, where);
}

}  // namespace mipnerf::ops
