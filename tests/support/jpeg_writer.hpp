// A JPEG encoder for tests (libjpeg's compressor): the library only reads JPEGs, tests need some to read.
#pragma once

#include <jpeglib.h>

#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

namespace mipnerf::test {

// Writes rgb [height][width][3] in [0, 1] as a baseline JPEG of `quality` (1..100).
inline void write_jpeg(const std::string& path, unsigned width, unsigned height, const std::vector<float>& rgb,
                       int quality = 95) {
  std::FILE* out = std::fopen(path.c_str(), "wb");
  if (!out) throw std::runtime_error("cannot write " + path);
  jpeg_compress_struct info;
  jpeg_error_mgr errors;
  info.err = jpeg_std_error(&errors);
  jpeg_create_compress(&info);
  jpeg_stdio_dest(&info, out);
  info.image_width = width;
  info.image_height = height;
  info.input_components = 3;
  info.in_color_space = JCS_RGB;
  jpeg_set_defaults(&info);
  jpeg_set_quality(&info, quality, TRUE);
  jpeg_start_compress(&info, TRUE);
  std::vector<unsigned char> row(static_cast<size_t>(width) * 3);
  while (info.next_scanline < height) {
    for (size_t k = 0; k < row.size(); ++k) {
      const float v = rgb[static_cast<size_t>(info.next_scanline) * width * 3 + k];
      row[k] = static_cast<unsigned char>(v <= 0 ? 0 : v >= 1 ? 255 : v * 255.0f + 0.5f);
    }
    JSAMPROW rows[1] = {row.data()};
    jpeg_write_scanlines(&info, rows, 1);
  }
  jpeg_finish_compress(&info);
  jpeg_destroy_compress(&info);
  std::fclose(out);
}

}  // namespace mipnerf::test
