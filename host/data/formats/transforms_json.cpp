// A single transforms.json with every frame (instant-ngp and nerfstudio write them; so does `dataset import-colmap`):
// intrinsics fl_x, fl_y, cx, cy, w, h globally or per frame; every 8th frame held out (detail::parse_transforms_json).
#include "data/formats/formats.hpp"

namespace mipnerf::data {
namespace {

bool detect(const std::filesystem::path& path, bool is_file) {
  if (is_file) return path.extension() == ".json" && path.filename() != "metadata.json";
  return std::filesystem::is_regular_file(path / "transforms.json");
}

std::vector<detail::SplitSpec> parse(const std::string& path, const LoadOptions& options) {
  return detail::parse_transforms_json(format_file(path, "transforms.json"), options);
}

// Photos taken all around (what `dataset from-photos` writes here for a capture that is not forward-facing): the
// poses alone tell, from every frame of the file.
void add_traits(const std::string& path, const LoadOptions& options, SceneTraits& traits) {
  LoadOptions every_frame = options;
  every_frame.splits = {};
  every_frame.holdout_every = 0;
  every_frame.world_around_cameras = false;
  every_frame.log = nullptr;
  std::vector<Matrix34> poses;
  for (const auto& split : parse(path, every_frame)) {
    for (const auto& frame : split.frames) poses.push_back(frame.camera_to_world);
  }
  traits.all_around = !poses.empty() && !looks_forward(poses);
}

SceneEffects effects(const SceneTraits& traits) { return object_or_photo_effects(traits, "transforms.json"); }

}  // namespace

const FormatReader kTransformsJsonFormat = {
    DatasetFormat::transforms_json, "transforms.json", detect, parse, add_traits, effects, nullptr,
    /*scales_on_disk=*/false, /*pyramid_source=*/true, /*ndc_bounds=*/false};

}  // namespace mipnerf::data
