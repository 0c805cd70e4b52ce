// The Blender format: DIR/transforms_{train,val,test}.json, frames with file_path and transform_matrix, one
// camera_angle_x per split, RGBA PNGs (detail::parse_blender, data/formats/transforms_parse.cpp).
#include "data/formats/formats.hpp"

namespace mipnerf::data {
namespace {

bool detect(const std::filesystem::path& path, bool is_file) {
  if (is_file) return false;
  for (const char* split : {"transforms_train.json", "transforms_val.json", "transforms_test.json"}) {
    if (std::filesystem::is_regular_file(path / split)) return true;
  }
  return false;
}

void add_traits(const std::string&, const LoadOptions&, SceneTraits&) {}

SceneEffects effects(const SceneTraits& traits) { return object_or_photo_effects(traits, "Blender"); }

}  // namespace

const FormatReader kBlenderFormat = {DatasetFormat::blender,
                                     "Blender (transforms_<split>.json)",
                                     detect,
                                     detail::parse_blender,
                                     add_traits,
                                     effects,
                                     nullptr,
                                     /*scales_on_disk=*/false,
                                     /*pyramid_source=*/true,
                                     /*ndc_bounds=*/false};

}  // namespace mipnerf::data
