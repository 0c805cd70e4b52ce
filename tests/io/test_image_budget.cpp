// Decompression bombs: a PNG or JPEG whose header declares far more pixels than its few bytes of data make obvious
// is refused from the header, with one line naming the file and the memory it would take, before the reader
// allocates for it (peak RSS measured); the budget (io/image_budget.hpp) is a setting, and images within it decode.
#include <doctest/doctest.h>

#include <sys/resource.h>
#include <zlib.h>

#include <cstdio>  // before jpeglib.h, which uses FILE and size_t without including them
#include <jpeglib.h>

#include <cstring>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "io/image_budget.hpp"
#include "io/jpeg.hpp"
#include "io/png.hpp"
#include "support/data_fixtures.hpp"

using namespace mipnerf;
using test::contains;
using test::error_of;

namespace {

// Peak resident memory of this process so far, in KiB. CTest runs each test case in a process of its own, so the
// growth across a call is what that call made resident.
long peak_rss_kib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

void append_chunk(std::vector<unsigned char>& png, const char* type, const std::vector<unsigned char>& data) {
  auto u32 = [&png](uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8) png.push_back(static_cast<unsigned char>(v >> shift));
  };
  u32(static_cast<uint32_t>(data.size()));
  const size_t start = png.size();
  png.insert(png.end(), type, type + 4);
  png.insert(png.end(), data.begin(), data.end());
  u32(static_cast<uint32_t>(crc32(0, png.data() + start, static_cast<uInt>(png.size() - start))));
}

// A valid 1-bit grey PNG of side x side pixels, every one black: deflate stores its rows of zeros ~1000:1.
std::vector<unsigned char> one_bit_black_png(uint32_t side) {
  std::vector<unsigned char> raw(static_cast<size_t>(side) * (1 + side / 8), 0);
  std::vector<unsigned char> idat(compressBound(static_cast<uLong>(raw.size())));
  uLongf idat_size = static_cast<uLongf>(idat.size());
  REQUIRE(compress2(idat.data(), &idat_size, raw.data(), static_cast<uLong>(raw.size()), 9) == Z_OK);
  idat.resize(idat_size);
  std::vector<unsigned char> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  const unsigned char s[4] = {static_cast<unsigned char>(side >> 24), static_cast<unsigned char>(side >> 16),
                              static_cast<unsigned char>(side >> 8), static_cast<unsigned char>(side)};
  append_chunk(png, "IHDR", {s[0], s[1], s[2], s[3], s[0], s[1], s[2], s[3], 1, 0, 0, 0, 0});
  append_chunk(png, "IDAT", idat);
  append_chunk(png, "IEND", {});
  return png;
}

// A 16x12 progressive JPEG whose start-of-frame then claims width x height: libjpeg allocates a progressive image's
// whole coefficient buffer when the decode starts, from the header alone.
std::vector<unsigned char> progressive_jpeg_claiming(uint16_t width, uint16_t height) {
  jpeg_compress_struct info;
  jpeg_error_mgr errors;
  info.err = jpeg_std_error(&errors);
  jpeg_create_compress(&info);
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
  jpeg_mem_dest(&info, &buffer, &size);
  info.image_width = 16;
  info.image_height = 12;
  info.input_components = 3;
  info.in_color_space = JCS_RGB;
  jpeg_set_defaults(&info);
  jpeg_simple_progression(&info);
  jpeg_start_compress(&info, TRUE);
  std::vector<unsigned char> row(16 * 3, 128);
  while (info.next_scanline < info.image_height) {
    JSAMPROW rows[1] = {row.data()};
    jpeg_write_scanlines(&info, rows, 1);
  }
  jpeg_finish_compress(&info);
  jpeg_destroy_compress(&info);
  std::vector<unsigned char> jpeg(buffer, buffer + size);
  std::free(buffer);
  for (size_t i = 0; i + 9 < jpeg.size(); ++i) {
    if (jpeg[i] == 0xFF && jpeg[i + 1] == 0xC2) {  // SOF2: length (2), precision (1), height (2), width (2)
      jpeg[i + 5] = static_cast<unsigned char>(height >> 8);
      jpeg[i + 6] = static_cast<unsigned char>(height);
      jpeg[i + 7] = static_cast<unsigned char>(width >> 8);
      jpeg[i + 8] = static_cast<unsigned char>(width);
      return jpeg;
    }
  }
  FAIL("no SOF2 marker in the progressive JPEG");
  return {};
}

// Sets the budget for the scope and gives the default back.
struct BudgetInScope {
  explicit BudgetInScope(uint64_t bytes) { io::set_image_budget_bytes(bytes); }
  ~BudgetInScope() { io::set_image_budget_bytes(io::kDefaultImageBudgetBytes); }
};

}  // namespace

TEST_CASE("image budget: a 33 KB PNG of 16384x16384 is refused from its header, in one line, allocating nothing") {
  const std::vector<unsigned char> bomb = one_bit_black_png(16384);
  CHECK(bomb.size() < 64 * 1024);  // what the fuzz runs may generate (-max_len=65536)
  const long before = peak_rss_kib();
  const std::string message = error_of([&] { io::decode_png(bomb.data(), bomb.size(), "bomb.png"); });
  const long grown = peak_rss_kib() - before;
  MESSAGE("peak RSS grew " << grown << " KiB; " << message);
  // 16384² pixels of 8-bit RGBA (4 B) and float RGBA (16 B): 5,120 MiB against the default 2,048.
  CHECK(message == "bomb.png: a 16384x16384 image needs 5120 MiB to decode (8-bit RGBA and float RGBA), more than "
                   "the 2048 MiB one image may take: downsample it, or raise the limit with mipnerf-cl --max-image-mib");
  CHECK(grown < 16 * 1024);  // libpng's row buffers and zlib's window: a few MiB at most
}

TEST_CASE("image budget: a progressive JPEG header claiming 60000x60000 is refused before libjpeg allocates") {
  const std::vector<unsigned char> bomb = progressive_jpeg_claiming(60000, 60000);
  const long before = peak_rss_kib();
  const std::string message = error_of([&] { io::decode_jpeg(bomb.data(), bomb.size(), "bomb.jpg"); });
  const long grown = peak_rss_kib() - before;
  MESSAGE("peak RSS grew " << grown << " KiB; " << message);
  CHECK(contains(message, "bomb.jpg: a 60000x60000 image needs 127030 MiB to decode (8-bit rows, float RGB and RGBA)"));
  CHECK(message.find('\n') == std::string::npos);
  CHECK(grown < 16 * 1024);
  // The same file claiming its true 16x12 decodes (the bomb is the header, not a broken file).
  const std::vector<unsigned char> honest = progressive_jpeg_claiming(16, 12);
  CHECK(io::decode_jpeg(honest.data(), honest.size(), "honest.jpg").rgb.size() == 16 * 12 * 3);
}

TEST_CASE("image budget: the budget is a setting: an image over it is refused, within it decodes") {
  const std::vector<unsigned char> png = one_bit_black_png(512);  // 512² x 20 B = 5 MiB to decode
  {
    const BudgetInScope four_mib(4 << 20);
    CHECK(contains(error_of([&] { io::decode_png(png.data(), png.size(), "a.png"); }),
                   "a.png: a 512x512 image needs 5 MiB to decode (8-bit RGBA and float RGBA), more than the 4 MiB"));
  }
  const BudgetInScope six_mib(6 << 20);
  const io::PngImage image = io::decode_png(png.data(), png.size(), "a.png");
  CHECK(image.width == 512);
  CHECK(image.rgba[0] == 0.0f);
  CHECK(image.rgba[3] == 1.0f);
}
