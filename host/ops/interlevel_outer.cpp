// Host wrapper of kernels/interlevel_outer.cl.
#include "ops/interlevel_outer.hpp"

#include "cl/launch.hpp"
#include "core/error.hpp"
#include "ops/stage_checks.hpp"

namespace mipnerf::ops {

double outer_interlevel_loss_value(const std::vector<float>& ray_loss, size_t batch_rays, size_t n_intervals,
                                   float mult) {
  return detail::mean_interlevel_loss(ray_loss, batch_rays, n_intervals, mult, "outer interlevel loss");
}

OuterInterlevel::OuterInterlevel(ocl::Context& ctx) : ctx_(&ctx) {
  auto& program = ctx.program({"interlevel_outer.cl"});
  fwd_ = &program.kernel("outer_interlevel_fwd");
  bwd_ = &program.kernel("outer_interlevel_bwd");
}

void OuterInterlevel::fwd(const InterlevelInputs& in, ocl::DeviceArray<float>& ray_loss) {
  const std::string where = "outer_interlevel_fwd";
  detail::check_interlevel_inputs(in, where);
  detail::require(ray_loss, in.n_rays, where);
  if (in.n_rays == 0) return;
  ocl::set_args(*fwd_, where, in.c, in.w, in.cp, in.wp, ray_loss, static_cast<cl_uint>(in.n_rays),
                static_cast<cl_uint>(in.n_intervals), static_cast<cl_uint>(in.n_proposal));
  ocl::launch_1d(*ctx_, *fwd_, in.n_rays, where);
}

void OuterInterlevel::bwd(const InterlevelInputs& in, float mult, size_t batch_rays, ocl::DeviceArray<float>& d_wp,
                          float upstream) {
  const std::string where = "outer_interlevel_bwd";
  detail::check_interlevel_inputs(in, where);
  if (batch_rays < in.n_rays) {
    throw Error(where + ": a batch of " + std::to_string(batch_rays) + " rays cannot hold a chunk of " +
                std::to_string(in.n_rays));
  }
  detail::require(d_wp, in.n_rays * in.n_proposal, where);
  if (in.n_rays == 0) return;
  const double scale =
      static_cast<double>(upstream) * mult / (static_cast<double>(batch_rays) * static_cast<double>(in.n_intervals));
  ocl::set_args(*bwd_, where, in.c, in.w, in.cp, in.wp, static_cast<float>(scale), d_wp,
                static_cast<cl_uint>(in.n_rays), static_cast<cl_uint>(in.n_intervals),
                static_cast<cl_uint>(in.n_proposal));
  ocl::launch_1d(*ctx_, *bwd_, in.n_rays, where);
}

}  // namespace mipnerf::ops
