// The paper's multiscale Blender format: DIR/metadata.json as mip-NeRF's convert_blender_data.py (or `mipnerf-cl
// make-multiscale`) writes it, every image at several scales with its lossmult (detail::parse_multiscale_metadata).
#include "core/error.hpp"
#include "data/formats/formats.hpp"

namespace mipnerf::data {
namespace {

bool detect(const std::filesystem::path& path, bool is_file) {
  if (is_file) return path.filename() == "metadata.json";
  return std::filesystem::is_regular_file(path / "metadata.json");
}

std::vector<detail::SplitSpec> parse(const std::string& path, const LoadOptions& options) {
  if (options.scales > 1) {
    throw Error(path +
                ": is already multiscale (metadata.json); load it with 1 scale, or build scales on the fly "
                "from the full-resolution Blender folder");
  }
  return detail::parse_multiscale_metadata(format_file(path, "metadata.json"), options);
}

void add_traits(const std::string&, const LoadOptions&, SceneTraits& traits) { traits.multiscale = true; }

SceneEffects effects(const SceneTraits& traits) { return object_or_photo_effects(traits, "multiscale Blender"); }

}  // namespace

const FormatReader kMultiscaleBlenderFormat = {DatasetFormat::multiscale_blender,
                                               "multiscale Blender (metadata.json)",
                                               detect,
                                               parse,
                                               add_traits,
                                               effects,
                                               nullptr,
                                               /*scales_on_disk=*/true,
                                               /*pyramid_source=*/false,
                                               /*ndc_bounds=*/false};

}  // namespace mipnerf::data
