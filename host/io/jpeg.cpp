// JPEG decoding with libjpeg's error handler turned into an exception at the call site (setjmp/longjmp: libjpeg
// is C, and its default handler exits the process).
#include "io/jpeg.hpp"

#include <algorithm>
#include <climits>
#include <csetjmp>
#include <cstdlib>
#include <cstdio>
#include <jpeglib.h>
#include <jerror.h>

#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/file.hpp"
#include "io/image_budget.hpp"

namespace mipnerf::io {
namespace {

// What decoding one pixel allocates, checked against the image budget (io/image_budget.hpp) from the header alone,
// before libjpeg allocates anything for the image: its 8-bit RGB rows (3 bytes), our float RGB (12), the float RGBA the
// dataset reader makes of it (16), and a progressive file's coefficient buffer, which libjpeg allocates whole when
// the decode starts (up to 3 components of 2-byte coefficients: 6). A tiny progressive file can declare 65535x65535.
constexpr uint64_t kBytesPerPixel = 3 + 12 + 16 + 6;

struct ErrorManager {
  jpeg_error_mgr base;  // first: libjpeg sees an ErrorManager* as a jpeg_error_mgr*
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

extern "C" void on_jpeg_error(j_common_ptr info) {
  auto* manager = reinterpret_cast<ErrorManager*>(info->err);
  (*info->err->format_message)(info, manager->message);
  std::longjmp(manager->jump, 1);
}

// Corrupt-data warnings (extraneous bytes before a marker, a restart marker out of place) are common in camera
// files and harmless: the decode goes on, as viewers do. Missing image data is not: where the file ends
// (JWRN_JPEG_EOF) or a scan's data stops at a marker before every block is coded (JWRN_HIT_MARKER), libjpeg fills
// the rest with grey and only warns, so a truncated photo would train as a picture with a grey band. Both are errors
// here, which also stops a damaged header that claims a huge image at the first rows its data cannot fill.
extern "C" void on_jpeg_warning(j_common_ptr info, int level) {
  const int code = info->err->msg_code;
  if (level < 0 && (code == JWRN_JPEG_EOF || code == JWRN_HIT_MARKER)) on_jpeg_error(info);
}

// Decodes into `image`; false with manager.message set when libjpeg failed. Only trivially destructible locals
// live between setjmp and a longjmp back to it; `image` and its vector belong to the caller.
// The 8-bit samples grow row by row (`samples`, owned by the caller) rather than being allocated from the header's
// size up front: a damaged file that claims a huge image fails at its first missing row, not after a large
// allocation.
bool decode_into(const unsigned char* bytes, size_t size, JpegImage& image, std::vector<unsigned char>& samples,
                 ErrorManager& manager, bool& too_large, bool& cmyk, bool header_only) {
  const uint64_t budget = image_budget_bytes();
  jpeg_decompress_struct info;
  info.err = jpeg_std_error(&manager.base);
  manager.base.error_exit = on_jpeg_error;
  manager.base.emit_message = on_jpeg_warning;
  if (setjmp(manager.jump)) {
    jpeg_destroy_decompress(&info);
    return false;
  }
  jpeg_create_decompress(&info);
  // libjpeg's own allocations (the coefficient buffer, its work rows) stop at the budget with an error, too.
  info.mem->max_memory_to_use = static_cast<long>(std::min<uint64_t>(budget, LONG_MAX));
  jpeg_mem_src(&info, bytes, static_cast<unsigned long>(size));
  jpeg_read_header(&info, TRUE);
  image.width = info.image_width;
  image.height = info.image_height;
  if (header_only) {
    jpeg_destroy_decompress(&info);
    return true;
  }
  if (static_cast<uint64_t>(info.image_width) * info.image_height > budget / kBytesPerPixel) {
    too_large = true;
    jpeg_destroy_decompress(&info);
    return true;
  }
  if (info.jpeg_color_space == JCS_CMYK || info.jpeg_color_space == JCS_YCCK) {
    cmyk = true;
    jpeg_destroy_decompress(&info);
    return true;
  }
  info.out_color_space = JCS_RGB;
  jpeg_start_decompress(&info);
  image.width = info.output_width;
  image.height = info.output_height;
  const size_t row_samples = static_cast<size_t>(image.width) * 3;
  while (info.output_scanline < info.output_height) {
    const size_t y = info.output_scanline;
    samples.resize((y + 1) * row_samples);
    JSAMPROW rows[1] = {samples.data() + y * row_samples};
    jpeg_read_scanlines(&info, rows, 1);
  }
  jpeg_finish_decompress(&info);
  jpeg_destroy_decompress(&info);
  return true;
}

}  // namespace

bool looks_like_jpeg(const unsigned char* bytes, size_t size) {
  return size >= 3 && bytes[0] == 0xFF && bytes[1] == 0xD8 && bytes[2] == 0xFF;
}

namespace {

JpegImage decode(const unsigned char* bytes, size_t size, const std::string& name, bool header_only) {
  if (!looks_like_jpeg(bytes, size)) throw Error(name + ": not a JPEG file (no FF D8 FF start marker)");
  JpegImage image;
  std::vector<unsigned char> samples;
  ErrorManager manager{};
  bool too_large = false, cmyk = false;
  if (!decode_into(bytes, size, image, samples, manager, too_large, cmyk, header_only)) {
    throw Error(name + ": unreadable JPEG (" + manager.message + ")");
  }
  if (cmyk) throw Error(name + ": a CMYK JPEG; save it as RGB");
  if (too_large) {
    check_image_budget(name, image.width, image.height, kBytesPerPixel, "8-bit rows, float RGB and RGBA");
    throw Error(name + ": the JPEG is larger than one image may be");  // not reached: the check above throws
  }
  image.rgb.resize(samples.size());
  for (size_t k = 0; k < samples.size(); ++k) image.rgb[k] = samples[k] / 255.0f;
  return image;
}

}  // namespace

JpegImage decode_jpeg(const unsigned char* bytes, size_t size, const std::string& name) {
  return decode(bytes, size, name, false);
}

JpegSize read_jpeg_size(const std::string& path) {
  const std::vector<unsigned char> bytes = read_file_bytes(path);
  const JpegImage header = decode(bytes.data(), bytes.size(), path, true);
  return {header.width, header.height};
}

JpegImage read_jpeg(const std::string& path) {
  const std::vector<unsigned char> bytes = read_file_bytes(path);
  return decode_jpeg(bytes.data(), bytes.size(), path);
}

namespace {

// Only trivially destructible locals between setjmp and a longjmp out of libjpeg (see decode_into).
bool encode_into(uint32_t width, uint32_t height, const float* rgb, int quality, ErrorManager& manager,
                 unsigned char*& buffer, unsigned long& size) {
  jpeg_compress_struct info;
  info.err = jpeg_std_error(&manager.base);
  manager.base.error_exit = on_jpeg_error;
  if (setjmp(manager.jump)) {
    jpeg_destroy_compress(&info);
    return false;
  }
  jpeg_create_compress(&info);
  jpeg_mem_dest(&info, &buffer, &size);
  info.image_width = width;
  info.image_height = height;
  info.input_components = 3;
  info.in_color_space = JCS_RGB;
  jpeg_set_defaults(&info);
  jpeg_set_quality(&info, quality, TRUE);
  jpeg_start_compress(&info, TRUE);
  unsigned char row[3 * 65536];
  while (info.next_scanline < height) {
    const float* in = rgb + static_cast<size_t>(info.next_scanline) * width * 3;
    for (size_t k = 0; k < static_cast<size_t>(width) * 3; ++k) {
      const float v = in[k];
      row[k] = static_cast<unsigned char>(v <= 0.0f ? 0 : v >= 1.0f ? 255 : static_cast<int>(v * 255.0f + 0.5f));
    }
    JSAMPROW rows[1] = {row};
    jpeg_write_scanlines(&info, rows, 1);
  }
  jpeg_finish_compress(&info);
  jpeg_destroy_compress(&info);
  return true;
}

}  // namespace

std::vector<unsigned char> encode_jpeg(uint32_t width, uint32_t height, const float* rgb, int quality,
                                       const std::string& name) {
  if (width == 0 || height == 0 || width > 65535 || height > 65535) {
    throw Error(name + ": a JPEG is 1 to 65535 pixels wide and high, not " + std::to_string(width) + "x" +
                std::to_string(height));
  }
  if (quality < 1 || quality > 100) throw Error(name + ": JPEG quality must be 1 to 100");
  ErrorManager manager{};
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
  const bool ok = encode_into(width, height, rgb, quality, manager, buffer, size);
  std::vector<unsigned char> bytes;
  if (ok) bytes.assign(buffer, buffer + size);
  std::free(buffer);
  if (!ok) throw Error(name + ": cannot encode as JPEG (" + manager.message + ")");
  return bytes;
}

void write_jpeg(const std::string& path, uint32_t width, uint32_t height, const float* rgb, int quality) {
  const std::vector<unsigned char> bytes = encode_jpeg(width, height, rgb, quality, path);
  write_bytes_atomically(path, std::string(bytes.begin(), bytes.end()));
}

}  // namespace mipnerf::io
