// Host wrapper of kernels/render.cl.
#include "ops/render.hpp"

#include <cmath>
#include <string>

#include "cl/launch.hpp"
#include "core/error.hpp"
#include "ops/activations.hpp"
#include "ops/stage_checks.hpp"
#include "ops/vector_items.hpp"

namespace mipnerf::ops {
namespace {

// What every forward and backward reads besides the colours: densities, edges, directions.
void check_density_inputs(const RenderDensityInputs& in, const std::string& where) {
  detail::require(in.density, in.n_rays * in.n_samples, where);
  detail::require(in.t_edges, in.n_rays * (in.n_samples + 1), where);
  detail::require(in.rays.directions, 3 * in.n_rays, where);
  // The kernels index samples and edges in 32 bits (kernels/render.cl, "Indices").
  detail::to_uint(in.n_rays * (in.n_samples + 1), where, "edges");
}

// What every forward writes besides the composite: opacity, distance, weights.
void check_weights_outputs(const RenderWeightsOutputs& out, size_t n_rays, size_t n_samples, const std::string& where) {
  detail::require(out.acc, n_rays, where);
  detail::require(out.distance, n_rays, where);
  detail::require(out.weights, n_rays * n_samples, where);
}

void check_inputs(const RenderInputs& in, const std::string& where) {
  detail::require(in.rgb, 3 * in.n_rays * in.n_samples, where);
  detail::to_uint(3 * in.n_rays * in.n_samples, where, "colour values");
  check_density_inputs({in.density, in.t_edges, in.rays, in.n_rays, in.n_samples}, where);
}

// The noise's counter slot is level·2^24 + sample/4 (kernels/render.cl): 256 levels of fewer than 2^26 samples.
void check_noise_key(const DensityNoiseKey& noise, size_t n_samples, const std::string& where) {
  if (noise.level >= 256 || n_samples >= (size_t{1} << 26)) {
    throw Error(where + ": density noise keys 256 levels of fewer than 2^26 samples; got level " +
                std::to_string(noise.level) + " with " + std::to_string(n_samples) + " samples");
  }
}

}  // namespace

ocl::BuildOptions render_build_options(const RenderOptions& options, const ActivationOptions& activation) {
  auto build = activation_build_options(activation).define("BACKGROUND", static_cast<int>(options.background));
  if (options.opaque_background) build.define("OPAQUE_BACKGROUND", 1);  // off: the build options as they were
  if (!(options.density_noise >= 0.0f) || !std::isfinite(options.density_noise)) {
    throw Error("render: density_noise must be finite and >= 0, not " + std::to_string(options.density_noise));
  }
  // Only when on: a program without it has no noise code at all.
  if (options.density_noise > 0.0f) build.define_float("DENSITY_NOISE", options.density_noise);
  return build;
}

Render::Render(ocl::Context& ctx, const RenderOptions& options, const ActivationOptions& activation,
               RenderSampleLoop loop)
    : ctx_(&ctx),
      options_(options),
      loop_(items_for_device(ctx, loop, RenderSampleLoop::per_vector, RenderSampleLoop::per_ray)) {
  auto& program = ctx.program({"common.cl", "activations.cl", "render.cl"},
                              render_build_options(options, activation)
                                  .define("SAMPLES_IN_LOCKSTEP", loop_ == RenderSampleLoop::lockstep ? 1 : 0)
                                  .define("SAMPLES_PER_VECTOR", loop_ == RenderSampleLoop::per_vector ? 1 : 0));
  fwd_ = &program.kernel("render_fwd");
  bwd_ = &program.kernel("render_bwd");
  raw_fwd_ = &program.kernel("render_raw_fwd");
  raw_bwd_ = &program.kernel("render_raw_bwd");
  raw_weights_fwd_ = &program.kernel("render_raw_weights_fwd");
  raw_weights_bwd_ = &program.kernel("render_raw_weights_bwd");
}

void Render::launch_fwd(::cl::Kernel& kernel, const std::string& where, const RenderInputs& in,
                        const RenderOutputs& out, const DensityNoiseKey* noise) {
  check_inputs(in, where);
  detail::require(out.comp_rgb, 3 * in.n_rays, where);
  check_weights_outputs({out.acc, out.distance, out.weights}, in.n_rays, in.n_samples, where);
  const cl_uint n_rays = detail::to_uint(in.n_rays, where, "rays"),
                n_samples = detail::to_uint(in.n_samples, where, "samples");
  if (noise) {
    check_noise_key(*noise, in.n_samples, where);
    ocl::set_args(kernel, where, in.rgb, in.density, in.t_edges, in.rays.directions, out.comp_rgb, out.acc,
                  out.distance, out.weights, n_rays, n_samples, static_cast<cl_ulong>(noise->rng.seed),
                  static_cast<cl_uint>(noise->rng.step), static_cast<cl_uint>(noise->rng.first_ray),
                  static_cast<cl_uint>(noise->level));
  } else {
    ocl::set_args(kernel, where, in.rgb, in.density, in.t_edges, in.rays.directions, out.comp_rgb, out.acc,
                  out.distance, out.weights, n_rays, n_samples);
  }
  ocl::launch_1d(*ctx_, kernel, in.n_rays, where);
}

void Render::launch_bwd(::cl::Kernel& kernel, const std::string& where, const RenderInputs& in,
                        const ocl::DeviceArray<float>& weights, const RenderGradients& grads,
                        const RenderInputGradients& out, const DensityNoiseKey* noise) {
  check_inputs(in, where);
  detail::require(weights, in.n_rays * in.n_samples, where);
  detail::require(grads.d_comp_rgb, 3 * in.n_rays, where);
  if (grads.d_acc) detail::require(*grads.d_acc, in.n_rays, where);
  detail::require(out.d_rgb, 3 * in.n_rays * in.n_samples, where);
  detail::require(out.d_density, in.n_rays * in.n_samples, where);
  // Without d_acc (d_weights) the kernel never reads that argument; any valid buffer stands in for it.
  const ocl::DeviceArray<float>& d_acc = grads.d_acc ? *grads.d_acc : grads.d_comp_rgb;
  const cl_uint has_d_acc = grads.d_acc ? 1 : 0;
  if (grads.d_weights) detail::require(*grads.d_weights, in.n_rays * in.n_samples, where);
  const ocl::DeviceArray<float>& d_weights = grads.d_weights ? *grads.d_weights : grads.d_comp_rgb;
  const cl_uint has_d_weights = grads.d_weights ? 1 : 0;
  const cl_uint n_rays = detail::to_uint(in.n_rays, where, "rays"),
                n_samples = detail::to_uint(in.n_samples, where, "samples");
  if (noise) {
    check_noise_key(*noise, in.n_samples, where);
    ocl::set_args(kernel, where, in.rgb, in.density, in.t_edges, in.rays.directions, weights, grads.d_comp_rgb, d_acc,
                  has_d_acc, d_weights, has_d_weights, out.d_rgb, out.d_density, n_rays, n_samples, static_cast<cl_ulong>(noise->rng.seed),
                  static_cast<cl_uint>(noise->rng.step), static_cast<cl_uint>(noise->rng.first_ray),
                  static_cast<cl_uint>(noise->level));
  } else {
    ocl::set_args(kernel, where, in.rgb, in.density, in.t_edges, in.rays.directions, weights, grads.d_comp_rgb, d_acc,
                  has_d_acc, d_weights, has_d_weights, out.d_rgb, out.d_density, n_rays, n_samples);
  }
  ocl::launch_1d(*ctx_, kernel, in.n_rays, where);
}

void Render::fwd(const RenderInputs& in, const RenderOutputs& out) {
  launch_fwd(*fwd_, "render_fwd", in, out, nullptr);
}

void Render::bwd(const RenderInputs& in, const ocl::DeviceArray<float>& weights, const RenderGradients& grads,
                 const RenderInputGradients& out) {
  launch_bwd(*bwd_, "render_bwd", in, weights, grads, out, nullptr);
}

void Render::raw_fwd(const RenderInputs& raw, const RenderOutputs& out, const DensityNoiseKey& noise) {
  launch_fwd(*raw_fwd_, "render_raw_fwd", raw, out, &noise);
}

void Render::raw_weights_fwd(const RenderDensityInputs& raw, const RenderWeightsOutputs& out,
                             const DensityNoiseKey& noise) {
  const std::string where = "render_raw_weights_fwd";
  check_density_inputs(raw, where);
  check_weights_outputs(out, raw.n_rays, raw.n_samples, where);
  check_noise_key(noise, raw.n_samples, where);
  const cl_uint n_rays = detail::to_uint(raw.n_rays, where, "rays"),
                n_samples = detail::to_uint(raw.n_samples, where, "samples");
  ocl::set_args(*raw_weights_fwd_, where, raw.density, raw.t_edges, raw.rays.directions, out.acc, out.distance,
                out.weights, n_rays, n_samples, static_cast<cl_ulong>(noise.rng.seed),
                static_cast<cl_uint>(noise.rng.step), static_cast<cl_uint>(noise.rng.first_ray),
                static_cast<cl_uint>(noise.level));
  ocl::launch_1d(*ctx_, *raw_weights_fwd_, raw.n_rays, where);
}

void Render::raw_weights_bwd(const RenderDensityInputs& raw, const ocl::DeviceArray<float>& weights,
                             const ocl::DeviceArray<float>& d_weights, ocl::DeviceArray<float>& d_raw_density,
                             const DensityNoiseKey& noise) {
  const std::string where = "render_raw_weights_bwd";
  check_density_inputs(raw, where);
  const size_t rows = raw.n_rays * raw.n_samples;
  detail::require(weights, rows, where);
  detail::require(d_weights, rows, where);
  detail::require(d_raw_density, rows, where);
  check_noise_key(noise, raw.n_samples, where);
  const cl_uint n_rays = detail::to_uint(raw.n_rays, where, "rays"),
                n_samples = detail::to_uint(raw.n_samples, where, "samples");
  ocl::set_args(*raw_weights_bwd_, where, raw.density, raw.t_edges, raw.rays.directions, weights, d_weights,
                d_raw_density, n_rays, n_samples, static_cast<cl_ulong>(noise.rng.seed),
                static_cast<cl_uint>(noise.rng.step), static_cast<cl_uint>(noise.rng.first_ray),
                static_cast<cl_uint>(noise.level));
  ocl::launch_1d(*ctx_, *raw_weights_bwd_, raw.n_rays, where);
}

void Render::raw_bwd(const RenderInputs& raw, const ocl::DeviceArray<float>& weights, const RenderGradients& grads,
                     const RenderInputGradients& out, const DensityNoiseKey& noise) {
  launch_bwd(*raw_bwd_, "render_raw_bwd", raw, weights, grads, out, &noise);
}

}  // namespace mipnerf::ops
