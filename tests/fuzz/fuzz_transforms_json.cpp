// Fuzz target: a single-file DIR/transforms.json (fl_x, fl_y, cx, cy, w, h; every 8th frame held out), loaded by
// the real loader (data::load_dataset: parse_transforms_json, then every image it names). DIR is a folder with the
// seed corpora's images whose parent holds them too (fuzz::nested_folder): a frame that names "../images/0.png" (or
// an absolute path) names a real image outside DIR, and a load that succeeds must have read only files inside DIR.
#include <cmath>

#include "data/dataset.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace mipnerf;
  const auto& dir = fuzz::nested_folder();
  const auto file = dir / "transforms.json";
  fuzz::write_input(file, data, size);
  fuzz::expect_only_errors(dir.string(), [&] {
    const data::Dataset dataset = data::load_dataset(file.string());
    for (const auto& split : dataset.splits) {
      fuzz::check(split.rgb.size() == 3 * split.num_pixels(), "a split's pixels do not match its offsets");
      for (const auto& image : split.files) {
        fuzz::check(fuzz::lies_inside(image, dir), "an image outside the dataset's folder was read");
      }
      for (const auto& camera : split.cameras) {
        fuzz::check(std::isfinite(camera.focal_x_px) && std::isfinite(camera.focal_y_px) &&
                        std::isfinite(camera.center_x_px) && std::isfinite(camera.center_y_px),
                    "a camera's intrinsics are not finite");
      }
    }
  });
  return 0;
}
