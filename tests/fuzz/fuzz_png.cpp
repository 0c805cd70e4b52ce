// Fuzz target: PNG decoding from memory (io::decode_png, which read_png calls with a file's bytes). The reader's image
// budget (io/image_budget.hpp) is set to 64 MiB here, far below libFuzzer's 2 GiB memory limits: a deflate stream of
// 64 KiB (-max_len) can describe 500 million 1-bit pixels, and every such header must be refused by the budget, never
// decoded.
#include "fuzz_support.hpp"
#include "io/image_budget.hpp"
#include "io/png.hpp"

namespace {
constexpr uint64_t kFuzzBudgetBytes = uint64_t{64} << 20;
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace mipnerf;
  static const bool budget_set = [] {
    io::set_image_budget_bytes(kFuzzBudgetBytes);
    return true;
  }();
  (void)budget_set;
  fuzz::expect_only_errors("fuzz.png", [&] {
    const io::PngImage image = io::decode_png(data, size, "fuzz.png");
    fuzz::check(image.width > 0 && image.height > 0, "a decoded PNG is empty");
    // What the decode took: the samples as 8- or 16-bit RGBA, and their float copy.
    const uint64_t bytes_per_pixel = 4 * (image.bit_depth / 8) + 4 * sizeof(float);
    fuzz::check(static_cast<uint64_t>(image.width) * image.height * bytes_per_pixel <= kFuzzBudgetBytes,
                "a PNG over the image budget was decoded");
    fuzz::check(image.rgba.size() == static_cast<size_t>(image.width) * image.height * 4,
                "a decoded PNG's samples do not match its size");
    for (float v : image.rgba) fuzz::check(v >= 0.0f && v <= 1.0f, "a decoded sample is outside [0, 1]");
  });
  return 0;
}
