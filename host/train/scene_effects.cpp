// Scene effects from the data.
#include "train/scene_effects.hpp"

#include "data/scene_traits.hpp"

namespace mipnerf::train {

SceneEffects scene_effects(const std::string& data_path, int factor) {
  data::LoadOptions options;
  options.factor = static_cast<uint32_t>(factor);
  const data::SceneTraits traits = data::scene_traits(data_path, options);
  SceneEffects effects;
  if (traits.format == data::DatasetFormat::llff && !traits.llff_360) {
    effects.settings = {{"ray_shape", "cylinder"}, {"spherify", "false"}, {"background", "black"}};
    effects.summary = "forward-facing LLFF → NDC rays, cylinders, black background";
  } else if (traits.format == data::DatasetFormat::llff) {
    effects.settings = {{"ray_shape", "cone"}, {"spherify", "true"}, {"background", "black"}};
    effects.summary = "360° LLFF capture → spherified poses, world rays, cones, black background";
  } else {
    const std::string kind = traits.format == data::DatasetFormat::transforms_json ? "transforms.json" : "Blender";
    effects.settings = {{"ray_shape", "cone"}, {"background", traits.has_alpha ? "white" : "black"}};
    effects.summary = kind + (traits.has_alpha ? " with alpha → cones, white background"
                                               : " without alpha (photos) → cones, black background");
  }
  if (traits.multiscale) effects.summary += "; multiscale data → area-weighted loss";
  return effects;
}

std::map<std::string, std::string> with_scene_effects(const SceneEffects& effects,
                                                      std::map<std::string, std::string> explicit_settings,
                                                      std::string& line) {
  line = "scene: " + effects.summary;
  std::string kept;
  for (const auto& [name, value] : effects.settings) {
    const auto given = explicit_settings.find(name);
    if (given == explicit_settings.end()) {
      explicit_settings[name] = value;
    } else if (given->second != value) {
      kept += (kept.empty() ? "" : ", ") + name + " = " + given->second;
    }
  }
  if (!kept.empty()) line += " (given explicitly, kept: " + kept + ")";
  return explicit_settings;
}

}  // namespace mipnerf::train
