// Host wrapper of kernels/render.cl: volume rendering forward and backward, plain or fused with the activations.
#pragma once

#include <cstddef>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "cl/program.hpp"
#include "core/stage_options.hpp"
#include "ops/ray_bundle.hpp"

namespace mipnerf::ops {

// BACKGROUND, DENSITY_NOISE (defined only when options.density_noise > 0), and the activations' options.
ocl::BuildOptions render_build_options(const RenderOptions& options, const ActivationOptions& activation);

// For fwd/bwd the activated values; for raw_fwd/raw_bwd the MLP's raw outputs in the same layouts.
struct RenderInputs {
  const ocl::DeviceArray<float>& rgb;      // [R][N][3]
  const ocl::DeviceArray<float>& density;  // [R][N]
  const ocl::DeviceArray<float>& t_edges;  // [R][N+1]
  const RayBundle& rays;                   // reads directions, unnormalised (δ = Δt·|d|)
  size_t n_rays;                           // R ≤ rays.n_rays(): the bundle's first R rays
  size_t n_samples;                        // N
};

struct RenderOutputs {
  ocl::DeviceArray<float>& comp_rgb;  // [R][3]
  ocl::DeviceArray<float>& acc;       // [R]
  ocl::DeviceArray<float>& distance;  // [R] expected distance in t, clipped to [t_0, t_N]
  ocl::DeviceArray<float>& weights;   // [R][N]: resampling's input, and what the backward needs besides the inputs
};

// A level rendered for its weights only (render_raw_weights_fwd): no colours in, no composite out.
struct RenderDensityInputs {
  const ocl::DeviceArray<float>& density;  // [R][N] raw
  const ocl::DeviceArray<float>& t_edges;  // [R][N+1]
  const RayBundle& rays;                   // reads directions
  size_t n_rays;
  size_t n_samples;
};

struct RenderWeightsOutputs {
  ocl::DeviceArray<float>& acc;       // [R]
  ocl::DeviceArray<float>& distance;  // [R]
  ocl::DeviceArray<float>& weights;   // [R][N]
};

struct RenderGradients {
  const ocl::DeviceArray<float>& d_comp_rgb;  // [R][3] ∂L/∂comp_rgb
  const ocl::DeviceArray<float>* d_acc;       // [R] ∂L/∂acc, or nullptr when the loss does not use acc
  // [R][N] ∂L/∂w of a loss on the weights themselves (the distortion loss), added to the composite's; or nullptr.
  const ocl::DeviceArray<float>* d_weights = nullptr;
};

struct RenderInputGradients {
  ocl::DeviceArray<float>& d_rgb;      // [R][N][3] (∂L/∂raw_rgb for raw_bwd); overwritten
  ocl::DeviceArray<float>& d_density;  // [R][N]    (∂L/∂raw_density for raw_bwd); overwritten
};

// How the kernels walk their rays' samples (render.cl): each work-item through its own ray (per_ray); all rays of a
// work-group a sample at a time, a barrier after each (lockstep, SAMPLES_IN_LOCKSTEP), which PoCL's CPU device
// vectorises across rays (render_raw_fwd on 4,096 rays x 128 samples 24 against 9 ms on the AMD EPYC, per ray against
// lockstep); or a ray per item, 16 samples at a time as float16 (per_vector, SAMPLES_PER_VECTOR), which PoCL runs in
// full-width vector registers without gathers (bench/results/kernel_runtimes/kernel_runtimes_xeon.md). Lockstep gives the per-ray
// values bit for bit; per vector sums the forward's optical depth and composite in another order, within the same
// float32 bounds (render.cl).
enum class RenderSampleLoop { device_default, per_ray, lockstep, per_vector };

// Rendering for one BACKGROUND (and, for the fused kernels, one set of activations).
class Render {
 public:
  // device_default: per vector on PoCL's CPU device, per ray elsewhere.
  Render(ocl::Context& ctx, const RenderOptions& options, const ActivationOptions& activation = {},
         RenderSampleLoop loop = RenderSampleLoop::device_default);
  const RenderOptions& options() const { return options_; }
  RenderSampleLoop sample_loop() const { return loop_; }

  // Enqueues render_fwd.
  void fwd(const RenderInputs& in, const RenderOutputs& out);
  // Enqueues render_bwd. `weights` is the forward's output for these inputs (what the forward saves).
  void bwd(const RenderInputs& in, const ocl::DeviceArray<float>& weights, const RenderGradients& grads,
           const RenderInputGradients& out);
  // The fused activations_fwd + render_fwd, on raw MLP outputs (in.rgb, in.density hold raw values). With
  // options().density_noise > 0 each raw density gets its noise first, keyed by `noise` (ray i of the launch is ray
  // noise.rng.first_ray + i of the batch); without, `noise` is not used.
  void raw_fwd(const RenderInputs& raw, const RenderOutputs& out, const DensityNoiseKey& noise = {});
  // raw_fwd without the colour (render_raw_weights_fwd): the same acc, distance and weights from the raw densities
  // alone, for a level whose composite colour nothing reads (inference; see graph.hpp).
  void raw_weights_fwd(const RenderDensityInputs& raw, const RenderWeightsOutputs& out,
                       const DensityNoiseKey& noise = {});
  // The fused render_bwd + activations_bwd: gradients with respect to the raw outputs. `noise` must be the
  // forward's: the backward draws the same noise again.
  void raw_bwd(const RenderInputs& raw, const ocl::DeviceArray<float>& weights, const RenderGradients& grads,
               const RenderInputGradients& out, const DensityNoiseKey& noise = {});
  // The backward of raw_weights_fwd's weights (render_raw_weights_bwd): d_raw_density [R][N] (overwritten) from
  // d_weights [R][N] = ∂L/∂w, what a proposal level trains through (the interlevel loss's gradient arrives on its
  // weights). `weights` [R][N] are raw_weights_fwd's (or raw_fwd's) for these inputs; `noise` must be the forward's.
  // No colour and no background enters (the weights have none).
  void raw_weights_bwd(const RenderDensityInputs& raw, const ocl::DeviceArray<float>& weights,
                       const ocl::DeviceArray<float>& d_weights, ocl::DeviceArray<float>& d_raw_density,
                       const DensityNoiseKey& noise = {});

 private:
  // `noise`: the fused kernels' key (their last four arguments); nullptr for render_fwd/bwd, which have none.
  void launch_fwd(::cl::Kernel& kernel, const std::string& where, const RenderInputs& in, const RenderOutputs& out,
                  const DensityNoiseKey* noise);
  void launch_bwd(::cl::Kernel& kernel, const std::string& where, const RenderInputs& in,
                  const ocl::DeviceArray<float>& weights, const RenderGradients& grads, const RenderInputGradients& out,
                  const DensityNoiseKey* noise);
  ocl::Context* ctx_;
  RenderOptions options_;
  RenderSampleLoop loop_;  // never device_default
  ::cl::Kernel* fwd_;
  ::cl::Kernel* bwd_;
  ::cl::Kernel* raw_fwd_;
  ::cl::Kernel* raw_bwd_;
  ::cl::Kernel* raw_weights_fwd_;
  ::cl::Kernel* raw_weights_bwd_;
};

}  // namespace mipnerf::ops
