// Writing rendered images: PNG (8-bit, the network's sRGB-encoded colours as they are, like the training data)
// and OpenEXR (linear RGB, depth "Z" in scene units and accumulation "acc" as channels of one file), plus the
// error images of an evaluation. Every file is written atomically.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "data/dataset.hpp"
#include "eval/image_renderer.hpp"

namespace mipnerf::eval {

// Which files a render writes per image.
struct OutputFormats {
  bool png = true;
  bool exr = false;
  bool none() const { return !png && !exr; }
};
// "png" | "exr" | "both" | "none" (no image files: a render's video alone); throws mipnerf::Error naming the
// accepted values.
OutputFormats parse_output_formats(const std::string& name);
// The formats as a record names them: "png", "exr", "png, exr" or "none".
std::string output_formats_name(const OutputFormats& formats);

// Writes `stem`.png and/or `stem`.exr (stem: a path without extension); returns the paths written. The EXR's R, G, B
// are io::srgb_to_linear of the rendered colours, Z the expected depth, acc the accumulation; `attributes` go
// into its header.
std::vector<std::string> write_rendered_image(const std::string& stem, const RenderedImage& image,
                                              const OutputFormats& formats,
                                              const std::map<std::string, std::string>& attributes = {});

// An error image, [pixels][3] grey: the mean over channels of |rendered − truth| times `gain`, clamped to [0, 1]
// by the PNG writer (gain 4: an error of 0.25 or more is white).
std::vector<float> error_image(const float* rendered_rgb, const float* truth_rgb, size_t pixels, double gain);

// File stems of a split's images, by index: "VVV", the view's number (3 digits), with "_scaleJ" added when the split
// holds several scales ("004_scale2": view 4 downsampled ×4). A view's scales follow its full-resolution image.
std::vector<std::string> split_image_stems(const data::Split& split);

}  // namespace mipnerf::eval
