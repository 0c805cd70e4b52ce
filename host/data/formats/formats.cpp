// The table of dataset formats, its lookups, and what a scene is and calls for.
#include "data/formats/formats.hpp"

#include <array>

#include "core/error.hpp"
#include "data/image.hpp"

namespace mipnerf::data {
namespace fs = std::filesystem;
namespace {

template <typename... Rows>
constexpr std::array<const FormatReader*, sizeof...(Rows)> rows(const Rows*... row) {
  return {row...};
}

// One row per DatasetFormat, in the enum's order (format_reader checks the order, tests/data walks every value).
constexpr auto kRows = rows(&kBlenderFormat, &kMultiscaleBlenderFormat, &kTransformsJsonFormat, &kLlffFormat);
static_assert(kRows.size() == static_cast<size_t>(DatasetFormat::count),
              "every DatasetFormat needs its row in kRows (host/data/formats)");

}  // namespace

const std::vector<const FormatReader*>& format_readers() {
  // A folder holding metadata.json is multiscale even when transforms files sit beside it; Blender's per-split files
  // win over a lone transforms.json.
  static const std::vector<const FormatReader*> order = {&kMultiscaleBlenderFormat, &kBlenderFormat,
                                                         &kTransformsJsonFormat, &kLlffFormat};
  return order;
}

const FormatReader& format_reader(DatasetFormat format) {
  const size_t index = static_cast<size_t>(format);
  if (index >= kRows.size() || kRows[index]->format != format) {
    throw Error("internal error: dataset format " + std::to_string(index) + " has no row in host/data/formats");
  }
  return *kRows[index];
}

const FormatReader& detect_reader(const std::string& path) {
  std::error_code ec;
  const auto status = fs::status(path, ec);
  if (fs::exists(status)) {
    const bool is_file = fs::is_regular_file(status);
    for (const FormatReader* reader : format_readers()) {
      if (reader->detect(fs::path(path), is_file)) return *reader;
    }
  }
  throw_no_dataset(path);
}

std::string format_file(const std::string& path, const char* file_name) {
  return fs::is_regular_file(path) ? path : detail::join_path(path, file_name);
}

SceneTraits scene_traits(const std::string& path, const LoadOptions& options) {
  const FormatReader& reader = detect_reader(path);
  SceneTraits traits;
  traits.format = reader.format;
  LoadOptions one_split = options;
  one_split.splits = {"train"};
  reader.add_traits(path, one_split, traits);
  const auto specs = reader.parse(path, one_split);
  // Read through the one image reader that tells PNG from JPEG by content.
  if (!specs.empty() && !specs[0].frames.empty())
    traits.has_alpha = load_rgba_image(specs[0].frames[0].image_path).has_alpha;
  return traits;
}

SceneEffects scene_effects(const std::string& path, const LoadOptions& options) {
  const SceneTraits traits = scene_traits(path, options);
  SceneEffects effects = format_reader(traits.format).effects(traits);
  if (traits.multiscale) effects.summary += "; multiscale data → area-weighted loss";
  return effects;
}

SceneEffects forward_facing_ndc_effects(const std::string& kind) {
  SceneEffects effects;
  effects.settings = {{"ray_shape", "cylinder"}, {"background", "black"}, {"unit_viewdirs", "false"},
                      {"density_noise", "1"}};
  effects.summary = kind + " → NDC rays, cylinders, black background, raw view directions, density noise 1";
  return effects;
}

SceneEffects object_or_photo_effects(const SceneTraits& traits, const std::string& kind) {
  // Forward-facing photos (a phone capture, a COLMAP import with a lens) are what LLFF's conventions were made for.
  if (!traits.has_alpha && traits.forward_facing && traits.ndc_blocker.empty()) {
    return forward_facing_ndc_effects(kind + " of forward-facing photos");
  }
  SceneEffects effects;
  effects.settings = {{"ray_shape", "cone"}, {"background", traits.has_alpha ? "white" : "black"}};
  // A rendered object seen from all around (Blender's) is bounded: only photos bring the world behind them.
  const bool unbounded = traits.all_around && !traits.has_alpha;
  effects.summary = kind + (traits.has_alpha ? " with alpha → cones, white background"
                            : unbounded      ? " of photos taken all around (360°) → cones, black background"
                                             : " without alpha (photos) → cones, black background");
  if (!traits.has_alpha && traits.forward_facing) {
    effects.summary += " (forward-facing, but not NDC: " + traits.ndc_blocker + ")";
  }
  if (unbounded) add_unbounded(effects);
  return effects;
}

void add_unbounded(SceneEffects& effects) {
  effects.zipnerf_settings = {{"sampler", "proposal"}, {"unbounded", "true"}, {"ray_shape", "cone"}};
  effects.zipnerf_summary = "unbounded (contraction, proposal sampling spaced by the power ladder from 0 to 1e6)";
  effects.mipnerf_settings = {
      {"sampler", "proposal"}, {"unbounded", "true"}, {"ray_shape", "cone"}, {"pos_max_deg", "12"}};
  effects.mipnerf_summary =
      "unbounded as mip-NeRF 360 (frustums contracted, IPE 0..11 on 21 directions, proposal sampling spaced in "
      "disparity from 0.2 to 1e6)";
}

}  // namespace mipnerf::data
