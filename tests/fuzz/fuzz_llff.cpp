// Fuzz target: an LLFF capture's poses_bounds.npy (io::parse_npy, then the official re-posing), loaded by the real
// loader (data::load_dataset on DIR/llff, whose images/ and images_2/ hold three small PNGs each), then the
// capture's render path. The input's size picks the options, so every path is fuzzed: odd → factor 2 (images_2/),
// a multiple of 3 → spherify (a 360° capture).
#include <cmath>

#include "data/dataset.hpp"
#include "data/formats/llff_capture.hpp"
#include "fuzz_support.hpp"

namespace {

bool finite_camera(const mipnerf::Camera& camera) {
  for (double v : camera.camera_to_world) {
    if (!std::isfinite(v)) return false;
  }
  return std::isfinite(camera.focal_x_px) && camera.focal_x_px > 0 && std::isfinite(camera.near) &&
         std::isfinite(camera.far) && camera.far > camera.near;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace mipnerf;
  const auto dir = fuzz::scratch_folder() / "llff";
  fuzz::write_input(dir / "poses_bounds.npy", data, size);
  data::LoadOptions options;
  options.factor = size % 2 == 1 ? 2 : 1;
  options.llff.spherify = size % 3 == 0;
  fuzz::expect_only_errors(dir.string(), [&] {
    const data::Dataset dataset = data::load_dataset(dir.string(), options);
    for (const auto& split : dataset.splits) {
      for (const auto& camera : split.cameras) fuzz::check(finite_camera(camera), "a loaded LLFF camera is not finite");
    }
    const auto capture = data::read_llff(dir.string(), options);
    for (const auto& camera : data::llff_render_path(capture, options, 5)) {
      fuzz::check(finite_camera(camera), "an LLFF render path camera is not finite");
    }
  });
  return 0;
}
