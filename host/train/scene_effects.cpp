// Scene effects from the data.
#include "train/scene_effects.hpp"

#include "data/formats/formats.hpp"

namespace mipnerf::train {

SceneEffects scene_effects(const std::string& data_path, int factor) {
  data::LoadOptions options;
  options.factor = static_cast<uint32_t>(factor);
  return data::scene_effects(data_path, options);
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
