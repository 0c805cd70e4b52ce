// PNG reading (8- and 16-bit, any colour type, expanded to RGBA) and writing (8- or 16-bit RGB/RGBA),
// through libpng; every failure is a mipnerf::Error naming the file.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace mipnerf::io {

// A decoded PNG: samples as stored, scaled to [0, 1] (value / 255 or value / 65535), no colour-space or
// gamma conversion, alpha straight (PNG alpha is never premultiplied).
struct PngImage {
  uint32_t width = 0;
  uint32_t height = 0;
  int bit_depth = 8;         // of the file: 8 or 16 (1-, 2- and 4-bit files are expanded and report 8)
  bool has_alpha = false;    // the file had an alpha channel (or a tRNS chunk); otherwise alpha is 1
  std::vector<float> rgba;   // [height][width][4]
};

// Reads any PNG. Grey, palette and low-bit-depth images are expanded to RGBA. Throws mipnerf::Error
// "<path>: unreadable PNG (<libpng's reason>)…" for a missing, truncated, corrupt or non-PNG file.
PngImage read_png(const std::string& path);
// Same, from bytes in memory; `name` is used in error messages.
PngImage decode_png(const unsigned char* bytes, size_t size, const std::string& name);

// The width and height a PNG's header declares, read from its first 24 bytes (signature and IHDR) without
// decoding the image. Throws like read_png for a missing file or one that does not start as a PNG does.
struct PngSize {
  uint32_t width = 0, height = 0;
};
PngSize read_png_size(const std::string& path);

// Writes samples [height][width][channels] (channels 3 = RGB or 4 = RGBA) atomically (io/atomic_file.hpp).
void write_png8(const std::string& path, uint32_t width, uint32_t height, int channels, const uint8_t* samples);
void write_png16(const std::string& path, uint32_t width, uint32_t height, int channels, const uint16_t* samples);
// Float samples in [0, 1] (clamped, rounded to nearest) written with bit_depth 8 or 16.
void write_png(const std::string& path, uint32_t width, uint32_t height, int channels, const float* samples,
               int bit_depth = 8);

// Float samples in [0, 1] as write_png stores them at 8 bits (clamped, rounded to nearest, NaN as 0).
std::vector<uint8_t> quantize_8bit(const float* samples, size_t count);

// Encoders behind the writers (PNG bytes in memory).
std::vector<unsigned char> encode_png8(uint32_t width, uint32_t height, int channels, const uint8_t* samples);
std::vector<unsigned char> encode_png16(uint32_t width, uint32_t height, int channels, const uint16_t* samples);

}  // namespace mipnerf::io
