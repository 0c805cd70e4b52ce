// Host images: loading, the ×2 box filter and compositing.
#include "data/image.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "core/error.hpp"
#include "io/file.hpp"
#include "io/jpeg.hpp"
#include "io/png.hpp"

namespace mipnerf::data {
namespace {

// Whether a file is read as a JPEG: by its first bytes (the JPEG or the PNG signature), so a PNG named .jpg is the PNG
// it is; a file with neither signature goes to the decoder its extension claims, which then names the problem.
bool read_as_jpeg(const unsigned char* bytes, size_t size, const std::string& path) {
  static const unsigned char kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (io::looks_like_jpeg(bytes, size)) return true;
  if (size >= 8 && std::equal(kPngSignature, kPngSignature + 8, bytes)) return false;
  std::string extension = std::filesystem::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension == ".jpg" || extension == ".jpeg";
}

}  // namespace

bool has_image_extension(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension == ".png" || extension == ".jpg" || extension == ".jpeg";
}

RgbaImage load_rgba_image(const std::string& path) {
  const std::vector<unsigned char> bytes = io::read_file_bytes(path);
  if (read_as_jpeg(bytes.data(), bytes.size(), path)) {
    const io::JpegImage jpeg = io::decode_jpeg(bytes.data(), bytes.size(), path);
    RgbaImage image{jpeg.width, jpeg.height, std::vector<float>(static_cast<size_t>(jpeg.width) * jpeg.height * 4, 1.0f),
                    false, 8};
    for (size_t p = 0; p < jpeg.rgb.size() / 3; ++p) {
      for (int c = 0; c < 3; ++c) image.rgba[4 * p + c] = jpeg.rgb[3 * p + c];
    }
    return image;
  }
  io::PngImage png = io::decode_png(bytes.data(), bytes.size(), path);
  return RgbaImage{png.width, png.height, std::move(png.rgba), png.has_alpha, png.bit_depth};
}

ImageSize read_image_size(const std::string& path) {
  const std::vector<unsigned char> head = io::read_file_prefix(path, 8);
  if (read_as_jpeg(head.data(), head.size(), path)) {
    const io::JpegSize size = io::read_jpeg_size(path);
    return {size.width, size.height};
  }
  const io::PngSize size = io::read_png_size(path);
  return {size.width, size.height};
}

RgbaImage downsample2(const RgbaImage& image) {
  if (image.width % 2 != 0 || image.height % 2 != 0) {
    throw Error("box downsampling needs even sizes, got " + std::to_string(image.width) + "x" +
                std::to_string(image.height));
  }
  RgbaImage out{image.width / 2, image.height / 2, {}};
  out.rgba.resize(static_cast<size_t>(out.width) * out.height * 4);
  const size_t in_row = static_cast<size_t>(image.width) * 4;
  for (uint32_t y = 0; y < out.height; ++y) {
    for (uint32_t x = 0; x < out.width; ++x) {
      const float* top = image.rgba.data() + (2 * y) * in_row + (2 * x) * 4;
      const float* bottom = top + in_row;
      float* dst = out.rgba.data() + (static_cast<size_t>(y) * out.width + x) * 4;
      for (int c = 0; c < 4; ++c) dst[c] = 0.25f * (top[c] + top[4 + c] + bottom[c] + bottom[4 + c]);
    }
  }
  return out;
}

RgbaImage crop_top_left(const RgbaImage& image, uint32_t width, uint32_t height) {
  if (width > image.width || height > image.height) {
    throw Error("crop: " + std::to_string(width) + "x" + std::to_string(height) + " does not fit in a " +
                std::to_string(image.width) + "x" + std::to_string(image.height) + " image");
  }
  RgbaImage out{width, height, {}, image.has_alpha, image.bit_depth};
  out.rgba.resize(static_cast<size_t>(width) * height * 4);
  const size_t row = static_cast<size_t>(width) * 4;
  for (uint32_t y = 0; y < height; ++y) {
    const float* src = image.rgba.data() + static_cast<size_t>(y) * image.width * 4;
    std::copy(src, src + row, out.rgba.data() + y * row);
  }
  return out;
}

void composite(const RgbaImage& image, Background background, float* rgb_out) {
  const size_t pixels = static_cast<size_t>(image.width) * image.height;
  const float bg = background == Background::white ? 1.0f : 0.0f;
  for (size_t i = 0; i < pixels; ++i) {
    const float* in = image.rgba.data() + 4 * i;
    const float alpha = background == Background::none ? 1.0f : in[3];
    for (int c = 0; c < 3; ++c) rgb_out[3 * i + c] = in[c] * alpha + bg * (1.0f - alpha);
  }
}

}  // namespace mipnerf::data
