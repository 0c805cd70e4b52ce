// Host wrapper of kernels/interlevel.cl.
#include "ops/interlevel.hpp"

#include <cmath>

#include "cl/launch.hpp"
#include "core/error.hpp"
#include "ops/stage_checks.hpp"

namespace mipnerf::ops {

namespace detail {

double mean_interlevel_loss(const std::vector<float>& ray_loss, size_t batch_rays, size_t intervals, float mult,
                            const std::string& what) {
  if (batch_rays == 0 || intervals == 0) throw Error(what + ": a batch without rays or intervals");
  double sum = 0.0;
  for (float v : ray_loss) sum += v;
  return static_cast<double>(mult) * sum / (static_cast<double>(batch_rays) * static_cast<double>(intervals));
}

void check_interlevel_inputs(const InterlevelInputs& in, const std::string& where) {
  if (in.n_intervals == 0 || in.n_proposal == 0) {
    throw Error(where + ": histograms of " + std::to_string(in.n_intervals) + " NeRF and " +
                std::to_string(in.n_proposal) + " proposal intervals; each needs at least one");
  }
  require(in.c, in.n_rays * (in.n_intervals + 1), where);
  require(in.w, in.n_rays * in.n_intervals, where);
  require(in.cp, in.n_rays * (in.n_proposal + 1), where);
  require(in.wp, in.n_rays * in.n_proposal, where);
  to_uint(in.n_rays * (in.n_proposal + 1), where, "proposal edges");
  to_uint(in.n_rays * (in.n_intervals + 1), where, "NeRF edges");
}

}  // namespace detail

double interlevel_loss_value(const std::vector<float>& ray_loss, size_t batch_rays, size_t n_proposal, float mult) {
  return detail::mean_interlevel_loss(ray_loss, batch_rays, n_proposal, mult, "spline interlevel loss");
}

SplineInterlevel::SplineInterlevel(ocl::Context& ctx) : ctx_(&ctx) {
  auto& program = ctx.program({"interlevel.cl"});
  fwd_ = &program.kernel("spline_interlevel_fwd");
  bwd_ = &program.kernel("spline_interlevel_bwd");
}

void SplineInterlevel::fwd(const InterlevelInputs& in, float blur_halfwidth, ocl::DeviceArray<float>& w_blur,
                           ocl::DeviceArray<float>& ray_loss) {
  const std::string where = "spline_interlevel_fwd";
  detail::check_interlevel_inputs(in, where);
  if (!(blur_halfwidth > 0.0f) || !std::isfinite(blur_halfwidth)) {
    throw Error(where + ": blur half-width " + std::to_string(blur_halfwidth) +
                "; it must be positive and finite (the official blurs are 0.03 and 0.003)");
  }
  detail::require(w_blur, in.n_rays * in.n_proposal, where);
  detail::require(ray_loss, in.n_rays, where);
  if (in.n_rays == 0) return;
  ocl::set_args(*fwd_, where, in.c, in.w, in.cp, in.wp, blur_halfwidth, w_blur, ray_loss,
                static_cast<cl_uint>(in.n_rays), static_cast<cl_uint>(in.n_intervals),
                static_cast<cl_uint>(in.n_proposal));
  ocl::launch_1d(*ctx_, *fwd_, in.n_rays, where);
}

void SplineInterlevel::bwd(const InterlevelInputs& in, const ocl::DeviceArray<float>& w_blur, float mult,
                           size_t batch_rays, ocl::DeviceArray<float>& d_wp, float upstream) {
  const std::string where = "spline_interlevel_bwd";
  detail::check_interlevel_inputs(in, where);
  if (batch_rays < in.n_rays) {
    throw Error(where + ": a batch of " + std::to_string(batch_rays) + " rays cannot hold a chunk of " +
                std::to_string(in.n_rays));
  }
  const size_t values = in.n_rays * in.n_proposal;
  detail::require(w_blur, values, where);
  detail::require(d_wp, values, where);
  if (values == 0) return;
  const double scale =
      static_cast<double>(upstream) * mult / (static_cast<double>(batch_rays) * static_cast<double>(in.n_proposal));
  ocl::set_args(*bwd_, where, w_blur, in.wp, static_cast<float>(scale), d_wp, detail::to_uint(values, where, "values"));
  ocl::launch_1d(*ctx_, *bwd_, values, where);
}

}  // namespace mipnerf::ops
