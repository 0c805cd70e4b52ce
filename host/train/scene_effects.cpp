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
  if (family != ModelFamily::mipnerf) {
    effects.mipnerf_settings.clear();
    effects.mipnerf_summary.clear();
  }
  return effects;
}

namespace {

// A family's group (`group`, said by `summary` after `label`) added to `settings` where no explicit setting disagrees
// with any of it, else none of it; `line` says which.
std::map<std::string, std::string> with_family_group(const std::map<std::string, std::string>& group,
                                                     const std::string& summary, const std::string& label,
                                                     std::map<std::string, std::string> settings, std::string& line) {
  if (group.empty()) return settings;
  std::string against;
  for (const auto& [name, value] : group) {
    const auto given = settings.find(name);
    if (given != settings.end() && given->second != value) {
      against += (against.empty() ? "" : ", ") + name + " = " + given->second;
    }
  }
  if (!against.empty()) {
    line += "; " + label + " not " + summary + " (given explicitly: " + against + ")";
    return settings;
  }
  for (const auto& [name, value] : group) settings.emplace(name, value);
  line += "; " + label + " " + summary;
  return settings;
}

}  // namespace

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
  explicit_settings =
      with_family_group(effects.zipnerf_settings, effects.zipnerf_summary, "Zip-NeRF", std::move(explicit_settings), line);
  return with_family_group(effects.mipnerf_settings, effects.mipnerf_summary, "mip-NeRF", std::move(explicit_settings),
                           line);
}

}  // namespace mipnerf::train
