// Fuzz target: a camera path file (mipnerf-cl render --path FILE), read by data::read_camera_path. An odd-sized
// input gives the reader a default image size (as --size does), an even-sized one none, so both ways are fuzzed.
#include <cmath>

#include "data/paths/camera_path.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace mipnerf;
  const auto& dir = fuzz::scratch_folder();
  const auto file = dir / "path.json";
  fuzz::write_input(file, data, size);
  data::CameraPathDefaults defaults;
  if (size % 2 == 1) {
    defaults.width = 16;
    defaults.height = 12;
  }
  fuzz::expect_only_errors(file.string(), [&] {
    const auto cameras = data::read_camera_path(file.string(), defaults);
    fuzz::check(!cameras.empty(), "a camera path without cameras was accepted");
    for (const auto& camera : cameras) {
      fuzz::check(camera.width_px > 0 && camera.height_px > 0, "a camera has no pixels");
      fuzz::check(camera.focal_x_px > 0 && std::isfinite(camera.focal_x_px) && camera.focal_y_px > 0 &&
                      std::isfinite(camera.focal_y_px),
                  "a camera's focal length is not positive and finite");
      fuzz::check(camera.near >= 0 && camera.far > camera.near && std::isfinite(camera.far), "a camera's range is bad");
    }
  });
  return 0;
}
