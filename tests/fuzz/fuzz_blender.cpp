// Fuzz target: a Blender split file, DIR/transforms_train.json, loaded by the real loader (data::load_dataset:
// parse_blender, then every image it names) beside the scratch folder's small PNGs.
#include <cmath>

#include "data/dataset.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace mipnerf;
  const auto& dir = fuzz::scratch_folder();
  fuzz::write_input(dir / "transforms_train.json", data, size);
  fuzz::expect_only_errors(dir.string(), [&] {
    const data::Dataset dataset = data::load_dataset(dir.string());
    for (const auto& split : dataset.splits) {
      fuzz::check(split.num_images() > 0, "a loaded split has no images");
      fuzz::check(split.rgb.size() == 3 * split.num_pixels(), "a split's pixels do not match its offsets");
      for (const auto& camera : split.cameras) {
        fuzz::check(std::isfinite(camera.focal_x_px) && camera.focal_x_px > 0, "a camera's focal length is not positive");
      }
    }
  });
  return 0;
}
