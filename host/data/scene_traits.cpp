// Dataset traits from metadata and the first image.
#include "data/scene_traits.hpp"

#include <filesystem>

#include "data/frames.hpp"
#include "data/llff.hpp"
#include "io/png.hpp"

namespace mipnerf::data {
namespace fs = std::filesystem;

SceneTraits scene_traits(const std::string& path, const LoadOptions& options) {
  SceneTraits traits;
  traits.format = detect_format(path);
  LoadOptions one_split = options;
  one_split.splits = {"train"};
  const bool is_file = fs::is_regular_file(path);
  std::vector<detail::SplitSpec> specs;
  switch (traits.format) {
    case DatasetFormat::blender:
      specs = detail::parse_blender(path, one_split);
      break;
    case DatasetFormat::multiscale_blender:
      traits.multiscale = true;
      specs = detail::parse_multiscale_metadata(is_file ? path : detail::join_path(path, "metadata.json"), one_split);
      break;
    case DatasetFormat::transforms_json:
      specs = detail::parse_transforms_json(is_file ? path : detail::join_path(path, "transforms.json"), one_split);
      break;
    case DatasetFormat::llff: {
      LoadOptions forward = one_split;
      forward.spherify = false;  // the capture as it was taken
      traits.llff_360 = looks_360(read_llff(path, forward));
      specs = detail::parse_llff(path, forward);
      break;
    }
  }
  if (!specs.empty() && !specs[0].frames.empty()) traits.has_alpha = io::read_png(specs[0].frames[0].image_path).has_alpha;
  return traits;
}

}  // namespace mipnerf::data
