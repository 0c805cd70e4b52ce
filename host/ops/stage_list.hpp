// The one list of the ray-math stages (kernels/rays.cl … render.cl): each stage's program, the kernels it launches
// with their work-item unit, and every specialisation it supports. Two readers walk it, so neither keeps a list of
// its own: tests/ops/test_specialisations.cpp checks every specialisation against the CPU reference, and
// host/bench/kernel_bench times every kernel (with the CPU reference beside it, bench/reference). A stage or a
// specialisation added here is tested and benchmarked; a reader that does not know a listed stage or kernel fails.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/stage_options.hpp"

namespace mipnerf::ops {

// Every ray-math stage's options together: one point of the specialisation space. The defaults are the paper's
// Blender configuration while training (cone rays, depth-linear jittered sampling, white background, softplus
// density, IPE over degrees 0..15, view directions over 0..3 with the identity): what the benchmark runs.
struct RayMathOptions {
  RaysOptions rays;
  SampleOptions sample{false, true};  // depth-linear, jittered
  ResampleOptions resample;           // α = 0.01, blur, jittered
  GaussianOptions gaussian;           // cone
  RenderOptions render;               // white background
  ActivationOptions activation;       // softplus(x − 1), ε = 0.001
  EncodingOptions ipe;                // degrees 0..15: 96 features
  EncodingOptions view;               // degrees 0..3 + identity: 27 features
  RayMathOptions() {
    view.max_deg = 4;
    view.append_identity = true;
  }
};

// What one work item of a kernel is; a launch over R rays × N intervals has items(unit, R, N) of them.
enum class ItemUnit {
  rays,       // R
  edges,      // R·(N + 1): interval edges
  intervals,  // R·N, one Gaussian (or encoded row) each
  samples,    // R·N, one network output each
};
const char* unit_name(ItemUnit unit);  // "rays", "edges", "intervals", "samples"
size_t items(ItemUnit unit, size_t n_rays, size_t n_samples);

// The stages and the kernels of the list, as ids: every reader of the list (the specialisation test, the kernel
// benchmark, the benchmark's CPU reference) maps an id to what it does with a switch without a default, and the
// build's -Werror=switch makes a stage or kernel added here without its case in every reader a compile error.
enum class StageId { rays, sample, gaussian, encode, activations, render, resample };
enum class KernelId {
  rays_fwd,
  sample_stratified_fwd,
  gaussian_fwd,
  ipe_fwd,
  gaussian_ipe_fwd,
  pe_fwd,
  activations_fwd,
  activations_bwd,
  render_fwd,
  render_bwd,
  render_raw_fwd,
  render_raw_bwd,
  resample_fwd
};

// A kernel of a stage as the benchmark times it, with the default RayMathOptions.
struct StageKernel {
  KernelId id;
  std::string kernel;   // its name in the kernel file, e.g. "render_fwd"
  ItemUnit unit;        // what one work item is
  std::string setting;  // what the default options make of it, e.g. "white"; empty when nothing to say
  // The benchmark's row: "render_fwd (white)", or the kernel's name alone without a setting.
  std::string row() const;
};

// One specialisation of a stage: the default options with this stage's changed.
struct StageVariant {
  std::string name;  // e.g. "cylinder no-view jitter"; empty for the stage's plain default
  RayMathOptions options;
};

struct StageDescription {
  StageId id;
  std::string name;                    // the host/ops class in lower case: "rays", "encode", …
  std::string program;                 // its kernel files after common.cl, e.g. "gaussian.cl + encode.cl"
  std::vector<StageKernel> kernels;    // the kernels the benchmark times, in this order
  std::vector<StageVariant> variants;  // every specialisation, each checked against the CPU reference
};

// The stages in data-flow order, the order one level's pass runs them (resampling, fed by the rendering weights,
// last): rays, sample, gaussian, encode, activations, render, resample. The NeRF baseline's sample_merge_fwd and
// gaussian_points_fwd have no specialisations of their own and are left out (tests/ops/test_sample.cpp and
// test_gaussian.cpp check them). The concatenated-PE variant's gaussian_concat_pe_fwd is built only under
// MIPNERF_CONCAT_PE (a variant of one study, not a stage every scene runs) and is left out too
// (tests/ops/test_concat_pe.cpp checks it, with and without that option). render_raw_weights_fwd (rendering's coarse
// level: render_raw_fwd's code without the colour) is left out as well: tests/ops/test_render.cpp holds it bit for bit
// to render_raw_fwd on every background, with and without density noise, and renders time it in their "render" stage.
// So is its backward render_raw_weights_bwd (a proposal level's ∂L/∂raw_density from the interlevel loss's ∂L/∂w;
// the training graph's proposal rounds, sampler = proposal): render_raw_bwd's sweep fed by d_weights, which test_render.cpp checks
// against the reference for every density activation and bias and every sample walk, with and without density noise,
// and bit for bit against render_raw_bwd's density gradient.
// gaussian_ipe_axis_fwd is Encode's fused kernel per (row, axis), in a program of its own with the degrees compiled
// in: on CPUs with fp64 the "gaussian_ipe_fwd (fused)" row times it, as Encode::gaussian_ipe runs it there in place of
// gaussian_ipe_fwd (test_encode.cpp checks it against the reference and its sin/cos against long double).
// ipe_axis_fwd and pe_axis_fwd, the same program's IPE and PE per (row, axis), likewise stand in for ipe_fwd and
// pe_fwd there, and their rows time them (test_encode.cpp's IPE and PE tests run them on such devices).
const std::vector<StageDescription>& ray_math_stages();

}  // namespace mipnerf::ops
