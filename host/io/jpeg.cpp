// JPEG decoding with libjpeg's error handler turned into an exception at the call site (setjmp/longjmp: libjpeg
// is C, and its default handler exits the process).
#include "io/jpeg.hpp"

#include <csetjmp>
#include <cstdio>
#include <jpeglib.h>

#include "core/error.hpp"
#include "io/file.hpp"

namespace mipnerf::io {
namespace {

constexpr uint64_t kMaxPixels = uint64_t{1} << 28;

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

extern "C" void on_jpeg_warning(j_common_ptr, int) {}  // corrupt-data warnings: the decode goes on, as viewers do

// Decodes into `image`; false with manager.message set when libjpeg failed. Only trivially destructible locals
// live between setjmp and a longjmp back to it; `image` and its vector belong to the caller.
bool decode_into(const unsigned char* bytes, size_t size, JpegImage& image, std::vector<unsigned char>& row,
                 ErrorManager& manager, bool& too_large, bool& cmyk, bool header_only) {
  jpeg_decompress_struct info;
  info.err = jpeg_std_error(&manager.base);
  manager.base.error_exit = on_jpeg_error;
  manager.base.emit_message = on_jpeg_warning;
  if (setjmp(manager.jump)) {
    jpeg_destroy_decompress(&info);
    return false;
  }
  jpeg_create_decompress(&info);
  jpeg_mem_src(&info, bytes, static_cast<unsigned long>(size));
  jpeg_read_header(&info, TRUE);
  if (header_only) {
    image.width = info.image_width;
    image.height = info.image_height;
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
  if (static_cast<uint64_t>(info.output_width) * info.output_height > kMaxPixels) {
    too_large = true;
    jpeg_destroy_decompress(&info);
    return true;
  }
  image.width = info.output_width;
  image.height = info.output_height;
  image.rgb.resize(static_cast<size_t>(image.width) * image.height * 3);
  row.resize(static_cast<size_t>(image.width) * 3);
  while (info.output_scanline < info.output_height) {
    JSAMPROW rows[1] = {row.data()};
    const size_t y = info.output_scanline;
    jpeg_read_scanlines(&info, rows, 1);
    float* out = image.rgb.data() + y * image.width * 3;
    for (size_t k = 0; k < row.size(); ++k) out[k] = row[k] / 255.0f;
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
  std::vector<unsigned char> row;
  ErrorManager manager{};
  bool too_large = false, cmyk = false;
  if (!decode_into(bytes, size, image, row, manager, too_large, cmyk, header_only)) {
    throw Error(name + ": unreadable JPEG (" + manager.message + ")");
  }
  if (cmyk) throw Error(name + ": a CMYK JPEG; save it as RGB");
  if (too_large) throw Error(name + ": a JPEG of more than 2^28 pixels; downsample it first");
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

}  // namespace mipnerf::io
