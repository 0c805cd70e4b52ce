// Host wrapper of kernels/render.cl.
#include "ops/render.hpp"

#include "cl/launch.hpp"
#include "ops/activations.hpp"
#include "ops/stage_checks.hpp"

namespace mipnerf::ops {
namespace {

void check_inputs(const RenderInputs& in, const std::string& where) {
  detail::require(in.rgb, 3 * in.n_rays * in.n_samples, where);
  detail::require(in.density, in.n_rays * in.n_samples, where);
  detail::require(in.t_edges, in.n_rays * (in.n_samples + 1), where);
  detail::require(in.rays.directions, 3 * in.n_rays, where);
  detail::to_uint(in.n_rays * in.n_samples, where, "rows");
}

}  // namespace

ocl::BuildOptions render_build_options(const RenderOptions& options, const ActivationOptions& activation) {
  return activation_build_options(activation).define("BACKGROUND", static_cast<int>(options.background));
}

Render::Render(ocl::Context& ctx, const RenderOptions& options, const ActivationOptions& activation)
    : ctx_(&ctx), options_(options) {
  auto& program = ctx.program({"common.cl", "activations.cl", "render.cl"}, render_build_options(options, activation));
  fwd_ = &program.kernel("render_fwd");
  bwd_ = &program.kernel("render_bwd");
  raw_fwd_ = &program.kernel("render_raw_fwd");
  raw_bwd_ = &program.kernel("render_raw_bwd");
}

void Render::launch_fwd(::cl::Kernel& kernel, const std::string& where, const RenderInputs& in,
                        const RenderOutputs& out) {
  check_inputs(in, where);
  detail::require(out.comp_rgb, 3 * in.n_rays, where);
  detail::require(out.acc, in.n_rays, where);
  detail::require(out.distance, in.n_rays, where);
  detail::require(out.weights, in.n_rays * in.n_samples, where);
  ocl::set_args(kernel, where, in.rgb, in.density, in.t_edges, in.rays.directions, out.comp_rgb, out.acc, out.distance,
                out.weights, detail::to_uint(in.n_rays, where, "rays"),
                detail::to_uint(in.n_samples, where, "samples"));
  ocl::launch_1d(*ctx_, kernel, in.n_rays, where);
}

void Render::launch_bwd(::cl::Kernel& kernel, const std::string& where, const RenderInputs& in,
                        const ocl::DeviceArray<float>& weights, const RenderGradients& grads,
                        const RenderInputGradients& out) {
  check_inputs(in, where);
  detail::require(weights, in.n_rays * in.n_samples, where);
  detail::require(grads.d_comp_rgb, 3 * in.n_rays, where);
  if (grads.d_acc) detail::require(*grads.d_acc, in.n_rays, where);
  detail::require(out.d_rgb, 3 * in.n_rays * in.n_samples, where);
  detail::require(out.d_density, in.n_rays * in.n_samples, where);
  // Without d_acc the kernel never reads that argument; any valid buffer stands in for it.
  const ocl::DeviceArray<float>& d_acc = grads.d_acc ? *grads.d_acc : grads.d_comp_rgb;
  ocl::set_args(kernel, where, in.rgb, in.density, in.t_edges, in.rays.directions, weights, grads.d_comp_rgb, d_acc,
                static_cast<cl_uint>(grads.d_acc ? 1 : 0), out.d_rgb, out.d_density,
                detail::to_uint(in.n_rays, where, "rays"), detail::to_uint(in.n_samples, where, "samples"));
  ocl::launch_1d(*ctx_, kernel, in.n_rays, where);
}

void Render::fwd(const RenderInputs& in, const RenderOutputs& out) { launch_fwd(*fwd_, "render_fwd", in, out); }

void Render::bwd(const RenderInputs& in, const ocl::DeviceArray<float>& weights, const RenderGradients& grads,
                 const RenderInputGradients& out) {
  launch_bwd(*bwd_, "render_bwd", in, weights, grads, out);
}

void Render::raw_fwd(const RenderInputs& raw, const RenderOutputs& out) {
  launch_fwd(*raw_fwd_, "render_raw_fwd", raw, out);
}

void Render::raw_bwd(const RenderInputs& raw, const ocl::DeviceArray<float>& weights, const RenderGradients& grads,
                     const RenderInputGradients& out) {
  launch_bwd(*raw_bwd_, "render_raw_bwd", raw, weights, grads, out);
}

}  // namespace mipnerf::ops
