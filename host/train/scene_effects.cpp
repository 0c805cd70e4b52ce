// Scene effects from the data.
#include "train/scene_effects.hpp"

#include "data/formats/formats.hpp"

namespace mipnerf::train {

SceneEffects scene_effects(const std::string& data_path, int factor, ModelFamily family) {
  data::LoadOptions options;
  options.factor = static_cast<uint32_t>(factor);
  SceneEffects effects = data::scene_effects(data_path, options);
  if (family != ModelFamily::zipnerf) {
    effects.zipnerf_settings.clear();
    effects.zipnerf_summary.clear();
  }
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
  if (effects.zipnerf_settings.empty()) return explicit_settings;
  std::string against;
  for (const auto& [name, value] : effects.zipnerf_settings) {
    const auto given = explicit_settings.find(name);
    if (given != explicit_settings.end() && given->second != value) {
      against += (against.empty() ? "" : ", ") + name + " = " + given->second;
    }
  }
  if (!against.empty()) {
    line += "; Zip-NeRF not " + effects.zipnerf_summary + " (given explicitly: " + against + ")";
    return explicit_settings;
  }
  for (const auto& [name, value] : effects.zipnerf_settings) explicit_settings.emplace(name, value);
  line += "; Zip-NeRF " + effects.zipnerf_summary;
  return explicit_settings;
}

}  // namespace mipnerf::train
