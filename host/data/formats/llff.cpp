// LLFF captures (forward-facing photos; 360° captures spherified): DIR/poses_bounds.npy and DIR/images[_<factor>]/,
// read with the official conventions (data/formats/llff_capture.hpp), and their official render paths.
#include "data/formats/llff_capture.hpp"

#include "data/formats/formats.hpp"

namespace mipnerf::data {
namespace {

bool detect(const std::filesystem::path& path, bool is_file) {
  return !is_file && std::filesystem::is_regular_file(path / "poses_bounds.npy");
}

void add_traits(const std::string& path, const LoadOptions& options, SceneTraits& traits) {
  LoadOptions as_taken = options;
  as_taken.llff.spherify = false;  // the capture as it was taken
  traits.all_around = looks_360(read_llff(path, as_taken));
}

// The official LLFF conventions: a forward-facing capture trains on NDC rays (cylinders) with the un-normalised world
// directions as view directions (datasets.py LLFF._generate_rays: viewdirs = rays.directions) and density noise 1
// (configs/llff.gin); a spherified 360° capture goes through the Blender ray generation (unit view directions), and
// Zip-NeRF trains it unbounded (bench/results/unbounded: ahead of the bounded grid at equal time on every seed).
SceneEffects effects(const SceneTraits& traits) {
  SceneEffects effects;
  if (traits.all_around) {
    // Both families contract the background (multinerf configs/360.gin, camp_zipnerf configs/zipnerf/360.gin).
    effects.settings = {{"ray_shape", "cone"},
                        {"spherify", "true"},
                        {"background", "black"},
                        {"unit_viewdirs", "true"},
                        {"density_noise", "0"}};
    effects.summary = "360° LLFF capture → spherified poses, world rays, cones, black background";
    add_unbounded(effects);
    return effects;
  }
  effects = forward_facing_ndc_effects("forward-facing LLFF");
  effects.settings["spherify"] = "false";
  return effects;
}

FormatRenderPath render_path(const std::string& path, const LoadOptions& options, int frames) {
  const LlffCapture capture = read_llff(path, options);
  FormatRenderPath out;
  out.cameras = llff_render_path(capture, options, frames);
  out.description = (capture.spherify ? "the spherical path of " : "the spiral of ") + path;
  out.kind = capture.spherify ? "llff spherical path" : "llff spiral";
  return out;
}

}  // namespace

const FormatReader kLlffFormat = {
    DatasetFormat::llff, "LLFF (poses_bounds.npy)", detect, detail::parse_llff, add_traits, effects, render_path,
    /*scales_on_disk=*/false, /*pyramid_source=*/false, /*ndc_bounds=*/true};

}  // namespace mipnerf::data
