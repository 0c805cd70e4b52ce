// Options of the ray-math stages (rays, sampling, resampling, Gaussians, encodings, rendering, activations):
// plain structs with the paper's defaults, shared by the OpenCL wrappers (host/ops) and the CPU reference
// (host/ref), so both always run the same specialisation. Compile-time options become -D defines; the rest are
// kernel arguments. The enums' name tables (enum_names) are the settings' vocabulary: train/config parses them.
#pragma once

#include <array>
#include <cstdint>

#include "core/enum_names.hpp"

namespace mipnerf {

// RAY_SHAPE: how an interval of a ray becomes a Gaussian (and, for rays, which space they live in).
enum class RayShape : int {
  cone = 0,      // conical frustums of the pixel's footprint (mip-NeRF)
  cylinder = 1,  // cylinders, rays in NDC space (forward-facing scenes, official LLFF)
};
constexpr std::array<EnumName<RayShape>, 2> enum_names(RayShape) {
  return {{{RayShape::cone, "cone"}, {RayShape::cylinder, "cylinder"}}};
}

// BACKGROUND: what shows through where acc < 1, and what the dataset composites its RGBA images onto (the
// values are the kernel's, so the enum is the -D define as it is).
enum class Background : int {
  none = 0,   // nothing added: a premultiplied colour (the caller composites with acc); same values as black
  black = 1,  // + 0·(1 − acc)
  white = 2,  // + 1·(1 − acc) (Blender scenes, paper §5)
};
// White first: the paper's choice for Blender scenes, listed first in help and errors.
constexpr std::array<EnumName<Background>, 3> enum_names(Background) {
  return {{{Background::white, "white"}, {Background::black, "black"}, {Background::none, "none"}}};
}

// DENSITY_ACTIVATION: what turns the MLP's raw density into a non-negative one.
enum class DensityActivation : int {
  softplus = 0,  // mip-NeRF
  relu = 1,      // NeRF baseline
};
constexpr std::array<EnumName<DensityActivation>, 2> enum_names(DensityActivation) {
  return {{{DensityActivation::softplus, "softplus"}, {DensityActivation::relu, "relu"}}};
}

// RAY_DISTANCE: how proposal sampling's normalised s ∈ [0, 1] maps to metric t ∈ [near, far] (official
// coord.construct_ray_warps with Model.raydist_fn).
enum class RayDistance : int {
  linear = 0,        // t = s·far + (1 − s)·near (raydist_fn = None: Blender, LLFF in NDC)
  power_ladder = 1,  // camp_zipnerf 360.gin: math.power_ladder with p = −3/2, premult 2 (unbounded scenes, near 0)
  reciprocal = 2,    // multinerf 360.gin: jnp.reciprocal, t = 1/(s/far + (1 − s)/near) (mip-NeRF 360; near > 0)
};
constexpr std::array<EnumName<RayDistance>, 3> enum_names(RayDistance) {
  return {{{RayDistance::linear, "linear"},
           {RayDistance::power_ladder, "power_ladder"},
           {RayDistance::reciprocal, "reciprocal"}}};
}

// Everything random is a function of (seed, step, ray): the ray's index in its batch is first_ray + (index in
// the launch), so a batch gives the same numbers however it is split into chunks.
struct RngKey {
  uint64_t seed = 0;
  uint32_t step = 0;
  uint32_t first_ray = 0;  // batch index of the launch's first ray
};

struct RaysOptions {
  RayShape ray_shape = RayShape::cone;  // RAY_SHAPE; cylinder → NDC rays (forward-facing scenes)
  float pixel_center_offset = 0.5f;     // PIXEL_CENTER_OFFSET: pixel (x, y) is sampled at (x + o, y + o)
  bool jitter_subpixel = false;         // SUBPIXEL_JITTER: a uniform position in the pixel instead (RngKey)
  bool view_dependence = true;          // VIEW_DEPENDENCE: off, viewdirs are not computed
  bool unit_viewdirs = true;            // UNIT_VIEWDIRS: unit viewdirs; false: the world directions as they are
  bool lens_tables = false;             // LENS_TABLES: cameras behind a lens read their rays from lens tables (cone)
  float ndc_near_plane = 1.0f;          // NDC_NEAR_PLANE (cylinder only), official 1
  // NDC_SCALE_X/Y (cylinder only): the run's NDC map, 2·f/size across and down (as float, the kernel's own
  // expression for the training cameras), used for every camera so that one of another field of view (a render path)
  // lands in the NDC the run trained in; 0: each camera's own (training, where every camera shares it).
  float ndc_scale_x = 0.0f, ndc_scale_y = 0.0f;
  // unit_viewdirs: the official Blender and spherified LLFF loaders normalise the view directions; the official
  // forward-facing LLFF loader passes viewdirs = rays.directions (camera-frame z = −1, taken before NDC).
};

struct SampleOptions {
  bool lindisp = false;    // SAMPLE_LINDISP: edges linear in disparity (needs near > 0) instead of depth
  bool randomized = true;  // jittered edges (training) or the deterministic bin edges (evaluation)
};

struct ResampleOptions {
  float padding = 0.01f;   // α added to every (blurred) weight (paper: 0.01; NeRF: 0)
  bool blur = true;        // blur-pool the weights first (mip-NeRF; NeRF: off)
  bool randomized = true;  // stratified u (training) or linspace u (evaluation)
};

// Proposal sampling's sampler (kernels/sample_intervals.cl; official stepfun.sample_intervals with models.py's
// resampling logits), in the normalised s-space.
struct SampleIntervalsOptions {
  float anneal = 1.0f;            // exponent on the weights: proposal_anneal(train_frac, anneal_slope) (official bias)
  float resample_padding = 0.0f;  // added to every weight before the log (official Model.resample_padding, default 0)
  float domain_near = 0.0f;       // the edges are clipped to [domain_near, domain_far] (official init_s_near,
  float domain_far = 1.0f;        //   init_s_far: 0 and 1 without near annealing)
  bool randomized = true;         // jittered u (training) or the deterministic centred linspace (rendering)
  bool single_jitter = true;      // one jitter per ray instead of one per sample (official default True)
};

struct GaussianOptions {
  RayShape ray_shape = RayShape::cone;  // RAY_SHAPE
};

// Degrees min_deg..max_deg−1 of a (integrated) positional encoding.
struct EncodingOptions {
  int min_deg = 0;
  int max_deg = 16;              // paper: IPE over 0..15 (96 features)
  bool append_identity = false;  // PE only: the raw input first (views: 0..3 + identity = 27 features)
  // The concatenated-PE variant only (kernels/encode.cl gaussian_concat_pe_fwd, supplement §7): degrees
  // 0..covariance_degrees−1 of the PE of the 6 signed square roots of the covariance's upper triangle (paper: 2).
  int covariance_degrees = 0;

  int degrees() const { return max_deg - min_deg; }
  // Features per row: 6L for IPE (identity never), 3·identity + 6L for PE, and the concatenated PE's
  // 3·identity + 6L + 12·L_cov (paper: 72 + 24 = 96).
  int ipe_width() const { return 6 * degrees(); }
  int pe_width() const { return (append_identity ? 3 : 0) + 6 * degrees(); }
  int concat_pe_width() const { return pe_width() + 12 * covariance_degrees; }
};

struct RenderOptions {
  Background background = Background::white;  // BACKGROUND
  // DENSITY_NOISE: the standard deviation of the N(0, 1) noise the fused render_raw_* kernels add to each raw density
  // before its activation (official MipNerfModel.density_noise, llff.gin: 1), drawn per (seed, step, ray, level,
  // sample) (DensityNoiseKey). 0 compiles it out. Training only: the graph builds rendering with 0.
  float density_noise = 0.0f;
  // OPAQUE_BACKGROUND: the last interval infinitely thick, so every ray's weights sum to 1 (mip-NeRF 360's
  // Model.opaque_background, multinerf configs/360.gin); nothing of the background colour then shows.
  bool opaque_background = false;
};

// What the density noise of one launch of render_raw_fwd/bwd is keyed by: the step's key (ray i of the launch is
// ray first_ray + i of the batch) and the level, so levels draw different numbers and a level's backward the same
// as its forward. Sample i of a ray takes draw i % 4 of rng_normal4(seed, ray, step, level·2^24 + i/4,
// RNG_STREAM_DENSITY_NOISE) (levels < 256, samples per ray < 2^26).
struct DensityNoiseKey {
  RngKey rng;
  uint32_t level = 0;
};

struct ActivationOptions {
  DensityActivation density = DensityActivation::softplus;  // DENSITY_ACTIVATION
  float density_bias = -1.0f;                               // DENSITY_BIAS (mip-NeRF −1; NeRF 0)
  float rgb_padding = 0.001f;                               // RGB_PADDING ε (mip-NeRF 0.001; NeRF 0: plain sigmoid)
};

}  // namespace mipnerf
