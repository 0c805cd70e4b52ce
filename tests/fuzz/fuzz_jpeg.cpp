// Fuzz target: JPEG decoding from memory (io::decode_jpeg, which read_jpeg calls with a file's bytes; captures and
// COLMAP projects hold photos), and the header-only size read the importers use to check images against cameras.
//
// As libjpeg-turbo's own fuzz targets do, images of more than kMaxFuzzPixels are not decoded: decoding a legitimately
// coded huge image (arithmetic coding makes a 2^28-pixel grey image a few kilobytes) takes longer than libFuzzer's
// per-input timeout under the sanitizers. Here the reader's own image budget (io/image_budget.hpp) is what refuses
// them, set to what kMaxFuzzPixels takes, so every huge header goes through the budget check, which must refuse it.
#include "fuzz_support.hpp"
#include "io/image_budget.hpp"
#include "io/jpeg.hpp"

namespace {
constexpr uint64_t kMaxFuzzPixels = uint64_t{1} << 22;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace mipnerf;
  // What decoding kMaxFuzzPixels takes through the reader (37 bytes a pixel: io/jpeg.cpp): a larger header is refused.
  static const bool budget_set = [] {
    io::set_image_budget_bytes(kMaxFuzzPixels * 37);
    return true;
  }();
  (void)budget_set;
  const auto path = fuzz::scratch_folder() / "fuzz.jpg";
  fuzz::write_input(path, data, size);
  fuzz::expect_only_errors(path.string(), [&] {
    const io::JpegSize header = io::read_jpeg_size(path.string());
    const bool over_budget = static_cast<uint64_t>(header.width) * header.height > kMaxFuzzPixels;
    const io::JpegImage image = io::decode_jpeg(data, size, path.string());
    fuzz::check(!over_budget, "a JPEG over the image budget was decoded");
    fuzz::check(image.width == header.width && image.height == header.height,
                "a decoded JPEG's size differs from its header's");
    fuzz::check(image.width > 0 && image.height > 0, "a decoded JPEG is empty");
    fuzz::check(image.rgb.size() == static_cast<size_t>(image.width) * image.height * 3,
                "a decoded JPEG's samples do not match its size");
    for (float v : image.rgb) fuzz::check(v >= 0.0f && v <= 1.0f, "a decoded sample is outside [0, 1]");
  });
  return 0;
}
