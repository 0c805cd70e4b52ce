// Fuzz target: the multiscale Blender DIR/metadata.json (as mip-NeRF's convert_blender_data.py writes it), loaded
// by the real loader (data::load_dataset: parse_multiscale_metadata, then every image it names).
#include <cmath>

#include "data/dataset.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace mipnerf;
  const auto& dir = fuzz::scratch_folder();
  const auto file = dir / "metadata.json";
  fuzz::write_input(file, data, size);
  fuzz::expect_only_errors(dir.string(), [&] {
    const data::Dataset dataset = data::load_dataset(file.string());
    for (const auto& split : dataset.splits) {
      fuzz::check(split.rgb.size() == 3 * split.num_pixels(), "a split's pixels do not match its offsets");
      for (const auto& camera : split.cameras) {
        fuzz::check(camera.lossmult > 0 && std::isfinite(camera.lossmult), "a camera's lossmult is not positive");
      }
    }
  });
  return 0;
}
