// Images of a dataset on the host: straight-alpha RGBA as read from a PNG, the official ×2 box
// downsampling, and compositing onto the background.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/stage_options.hpp"

namespace mipnerf::data {

// Straight (not premultiplied) RGBA, [height][width][4], values in [0, 1]: the stored 8- or 16-bit
// values / 255 (or / 65535), no gamma conversion. Like the official NeRF and mip-NeRF code we train on
// these sRGB-encoded values directly.
struct RgbaImage {
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<float> rgba;
  bool has_alpha = false;  // the file had an alpha channel (rendered objects); RGB files and JPEGs do not
  int bit_depth = 8;       // the file's bits per channel (PNG 8 or 16; JPEG 8): what a copy of it is written with
};

// Reads a PNG or a JPEG (told apart by their first bytes) as RGBA (RGB files and JPEGs get alpha 1). The one image
// reader of the datasets: every place that reads a dataset's image goes through it. Errors name the file.
RgbaImage load_rgba_image(const std::string& path);

// Whether a file's name says PNG or JPEG (.png, .jpg, .jpeg, any case): the images the readers take. What it holds
// is the reader's to find out (load_rgba_image tells them apart by their first bytes).
bool has_image_extension(const std::filesystem::path& path);

// Width and height from the file's header, PNG or JPEG told apart by their first bytes. Errors name the file.
struct ImageSize {
  uint32_t width = 0, height = 0;
};
ImageSize read_image_size(const std::string& path);

// One ×2 step of the multiscale pyramid, as the official mip-NeRF script (scripts/convert_blender_data.py,
// `down2`) builds it: every output pixel is the plain mean of a 2×2 block of the straight RGBA values,
// alpha included (not premultiplied). Width and height must be even.
RgbaImage downsample2(const RgbaImage& image);

// The top-left width x height pixels of `image` (width ≤ image.width, height ≤ image.height): a crop that keeps
// every kept pixel where it was, so a camera's intrinsics in pixels stay valid for it.
RgbaImage crop_top_left(const RgbaImage& image, uint32_t width, uint32_t height);

// rgb_out [height][width][3] = rgb · α + background · (1 − α), in the stored (sRGB-encoded) values, as the
// official code does (the paper composites Blender scenes onto white); Background::none drops alpha and keeps rgb
// as stored. Background is the renderer's (core/stage_options.hpp): the same choice made once for both.
void composite(const RgbaImage& image, Background background, float* rgb_out);

}  // namespace mipnerf::data
