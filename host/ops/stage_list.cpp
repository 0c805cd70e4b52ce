// The one list of the ray-math stages (see stage_list.hpp).
#include "ops/stage_list.hpp"

namespace mipnerf::ops {
namespace {

const char* shape_name(RayShape shape) { return shape == RayShape::cone ? "cone" : "cylinder"; }

// The NeRF baseline's activations: ReLU density without bias, plain sigmoid colour.
ActivationOptions nerf_activation() {
  ActivationOptions nerf;
  nerf.density = DensityActivation::relu;
  nerf.density_bias = 0.0f;
  nerf.rgb_padding = 0.0f;
  return nerf;
}

// Joins the non-empty words with spaces.
std::string words(std::initializer_list<std::string> parts) {
  std::string out;
  for (const auto& part : parts) {
    if (part.empty()) continue;
    out += (out.empty() ? "" : " ") + part;
  }
  return out;
}

// RAY_SHAPE × (VIEW_DEPENDENCE with UNIT_VIEWDIRS on or off, or no VIEW_DEPENDENCE, where UNIT_VIEWDIRS has nothing
// to change) × SUBPIXEL_JITTER: 2 × 3 × 2 = 12.
std::vector<StageVariant> rays_variants() {
  struct View {
    const char* name;
    bool view_dependence, unit_viewdirs;
  };
  const View views[] = {{"view", true, true}, {"view raw-viewdirs", true, false}, {"no-view", false, true}};
  std::vector<StageVariant> list;
  for (auto shape : {RayShape::cone, RayShape::cylinder}) {
    for (const View& view : views) {
      for (bool jitter : {false, true}) {
        StageVariant v{words({shape_name(shape), view.name, jitter ? "jitter" : ""}), {}};
        v.options.rays.ray_shape = shape;
        v.options.rays.view_dependence = view.view_dependence;
        v.options.rays.unit_viewdirs = view.unit_viewdirs;
        v.options.rays.jitter_subpixel = jitter;
        list.push_back(v);
      }
    }
  }
  return list;
}

// SAMPLE_LINDISP × randomized (a kernel argument, but the deterministic path is what rendering runs): 4.
std::vector<StageVariant> sample_variants() {
  std::vector<StageVariant> list;
  for (bool lindisp : {false, true}) {
    for (bool randomized : {false, true}) {
      StageVariant v{words({lindisp ? "lindisp" : "", randomized ? "jitter" : ""}), {}};
      v.options.sample = {lindisp, randomized};
      list.push_back(v);
    }
  }
  return list;
}

// RAY_SHAPE, for gaussian.cl alone and for the fused Gaussian + IPE (which includes it): 2.
std::vector<StageVariant> shape_variants() {
  std::vector<StageVariant> list;
  for (auto shape : {RayShape::cone, RayShape::cylinder}) {
    StageVariant v{shape_name(shape), {}};
    v.options.gaussian.ray_shape = shape;
    list.push_back(v);
  }
  return list;
}

// DENSITY_ACTIVATION, DENSITY_BIAS, RGB_PADDING as mip-NeRF and NeRF set them: 2.
std::vector<StageVariant> activation_variants() {
  std::vector<StageVariant> list{{"softplus", {}}, {"relu", {}}};
  list[1].options.activation = nerf_activation();
  return list;
}

// BACKGROUND × the two sets of activations (render.cl includes activations.cl): 6; and DENSITY_NOISE as forward-facing
// LLFF scenes train (official llff.gin: black background, softplus, noise 1): 7.
std::vector<StageVariant> render_variants() {
  std::vector<StageVariant> list;
  for (auto background : {Background::none, Background::black, Background::white}) {
    for (const auto& activation : activation_variants()) {
      StageVariant v{"background " + std::to_string(static_cast<int>(background)) + " " + activation.name,
                     activation.options};
      v.options.render.background = background;
      list.push_back(v);
    }
  }
  StageVariant noisy{"background 1 softplus density-noise", {}};
  noisy.options.render.background = Background::black;
  noisy.options.render.density_noise = 1.0f;
  list.push_back(noisy);
  return list;
}

// No compile-time options: blur-pool and padding are kernel arguments, as mip-NeRF and NeRF set them: 2.
std::vector<StageVariant> resample_variants() {
  std::vector<StageVariant> list{{"mipnerf", {}}, {"nerf", {}}};
  list[1].options.resample.padding = 0.0f;
  list[1].options.resample.blur = false;
  return list;
}

std::vector<StageDescription> make_stages() {
  using U = ItemUnit;
  using K = KernelId;
  return {
      {StageId::rays, "rays", "rays.cl", {{K::rays_fwd, "rays_fwd", U::rays, "cone"}}, rays_variants()},
      {StageId::sample,
       "sample",
       "sample.cl",
       {{K::sample_stratified_fwd, "sample_stratified_fwd", U::edges, "jittered"}},
       sample_variants()},
      {StageId::gaussian, "gaussian", "gaussian.cl", {{K::gaussian_fwd, "gaussian_fwd", U::intervals, "cone"}},
       shape_variants()},
      {StageId::encode,
       "encode",
       "gaussian.cl + encode.cl",
       {{K::ipe_fwd, "ipe_fwd", U::intervals, "L = 16, 96 features"},
        {K::gaussian_ipe_fwd, "gaussian_ipe_fwd", U::intervals, "fused"},
        {K::pe_fwd, "pe_fwd", U::rays, "view directions, 27 features"}},
       shape_variants()},
      {StageId::activations,
       "activations",
       "activations.cl",
       {{K::activations_fwd, "activations_fwd", U::samples, ""}, {K::activations_bwd, "activations_bwd", U::samples, ""}},
       activation_variants()},
      {StageId::render,
       "render",
       "activations.cl + render.cl",
       {{K::render_fwd, "render_fwd", U::samples, "white"},
        {K::render_bwd, "render_bwd", U::samples, "white"},
        {K::render_raw_fwd, "render_raw_fwd", U::samples, "fused activations"},
        {K::render_raw_bwd, "render_raw_bwd", U::samples, "fused activations"}},
       render_variants()},
      {StageId::resample,
       "resample",
       "resample.cl",
       {{K::resample_fwd, "resample_fwd", U::edges, "α = 0.01, jittered"}},
       resample_variants()},
  };
}

}  // namespace

const char* unit_name(ItemUnit unit) {
  switch (unit) {
    case ItemUnit::rays:
      return "rays";
    case ItemUnit::edges:
      return "edges";
    case ItemUnit::intervals:
      return "intervals";
    case ItemUnit::samples:
      return "samples";
  }
  return "?";
}

size_t items(ItemUnit unit, size_t n_rays, size_t n_samples) {
  switch (unit) {
    case ItemUnit::rays:
      return n_rays;
    case ItemUnit::edges:
      return n_rays * (n_samples + 1);
    case ItemUnit::intervals:
    case ItemUnit::samples:
      return n_rays * n_samples;
  }
  return 0;
}

std::string StageKernel::row() const { return setting.empty() ? kernel : kernel + " (" + setting + ")"; }

const std::vector<StageDescription>& ray_math_stages() {
  static const std::vector<StageDescription> stages = make_stages();
  return stages;
}

}  // namespace mipnerf::ops
