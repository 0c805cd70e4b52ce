// The effects a scene calls for, from its data rather than from the user: a forward-facing LLFF capture gets NDC
// rays cast as cylinders and a black background, a 360° capture of photos spherified poses, cones and its model
// family's unbounded contraction (mip-NeRF 360's for mip-NeRF, Zip-NeRF's for Zip-NeRF), rendered objects with alpha a
// white background, photos a black one, multiscale data the area-weighted loss. Settings given explicitly
// (config file, flags, --set) still win. Each effect is a compile-time option of the kernels, so a scene pays only
// for what it uses.
#pragma once

#include <map>
#include <string>

#include "data/formats/formats.hpp"
#include "train/config.hpp"

namespace mipnerf::train {

// The effects themselves are the dataset format's (data/formats: each row has its rule).
using data::SceneEffects;

// What the dataset at `data_path` calls for (`factor` picks an LLFF capture's images_<factor>/) from a model of
// `family`: each family's group (SceneEffects::zipnerf_settings, mipnerf_settings) is kept for that family alone.
SceneEffects scene_effects(const std::string& data_path, int factor, ModelFamily family = ModelFamily::mipnerf);

// `explicit_settings` with the effects added where the user gave no value; `line` becomes the one line `train`
// prints and config.json records ("scene: …", with any effect an explicit setting overrode). A family's effects are a
// group that works only together (unbounded needs proposal sampling and cones): added where no explicit setting
// disagrees with any of them, else left out, and the line says which explicit setting kept them out.
std::map<std::string, std::string> with_scene_effects(const SceneEffects& effects,
                                                      std::map<std::string, std::string> explicit_settings,
                                                      std::string& line);

}  // namespace mipnerf::train
