// JPEG reading and writing through libjpeg(-turbo) (Debian's libjpeg-dev): photos, as captures and COLMAP projects
// hold them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace mipnerf::io {

struct JpegImage {
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<float> rgb;  // [height][width][3], the stored (sRGB-encoded) values / 255
};

// Decodes a baseline or progressive JPEG of any colour space libjpeg converts to RGB (greyscale, YCbCr; CMYK is
// refused). Throws mipnerf::Error "<name>: unreadable JPEG (<libjpeg's reason>)" for corrupt or truncated data,
// and for images over 2^28 pixels.
JpegImage decode_jpeg(const unsigned char* bytes, size_t size, const std::string& name);
JpegImage read_jpeg(const std::string& path);
// The size from the file's header, without decoding it.
struct JpegSize {
  uint32_t width = 0, height = 0;
};
JpegSize read_jpeg_size(const std::string& path);

// The first bytes of a JPEG file (SOI marker FF D8 FF).
bool looks_like_jpeg(const unsigned char* bytes, size_t size);

// Encodes rgb [height][width][3] (values in [0, 1], clamped, rounded to 8 bits) as a baseline JPEG of `quality`
// (1..100) and writes it atomically. Throws mipnerf::Error naming the file when libjpeg or the write fails.
std::vector<unsigned char> encode_jpeg(uint32_t width, uint32_t height, const float* rgb, int quality,
                                       const std::string& name);
void write_jpeg(const std::string& path, uint32_t width, uint32_t height, const float* rgb, int quality = 95);

}  // namespace mipnerf::io
