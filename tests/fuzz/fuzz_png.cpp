// Fuzz target: PNG decoding from memory (io::decode_png, which read_png calls with a file's bytes).
#include "fuzz_support.hpp"
#include "io/png.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace mipnerf;
  fuzz::expect_only_errors("fuzz.png", [&] {
    const io::PngImage image = io::decode_png(data, size, "fuzz.png");
    fuzz::check(image.width > 0 && image.height > 0, "a decoded PNG is empty");
    fuzz::check(image.rgba.size() == static_cast<size_t>(image.width) * image.height * 4,
                "a decoded PNG's samples do not match its size");
    for (float v : image.rgba) fuzz::check(v >= 0.0f && v <= 1.0f, "a decoded sample is outside [0, 1]");
  });
  return 0;
}
