// PNG, EXR and error images of renders.
#include "eval/image_output.hpp"

#include <cmath>
#include <cstdio>

#include "core/error.hpp"
#include "io/color.hpp"
#include "io/exr.hpp"
#include "io/png.hpp"

namespace mipnerf::eval {

OutputFormats parse_output_formats(const std::string& name) {
  if (name == "png") return {true, false};
  if (name == "exr") return {false, true};
  if (name == "both") return {true, true};
  if (name == "none") return {false, false};
  throw Error("output format '" + name + "': expected png, exr or both (or none, with a video)");
}

std::string output_formats_name(const OutputFormats& formats) {
  if (formats.none()) return "none";
  return formats.png && formats.exr ? "png, exr" : formats.png ? "png" : "exr";
}

std::vector<std::string> write_rendered_image(const std::string& stem, const RenderedImage& image,
                                              const OutputFormats& formats,
                                              const std::map<std::string, std::string>& attributes) {
  std::vector<std::string> written;
  if (formats.png) {
    const std::string path = stem + ".png";
    io::write_png(path, image.width, image.height, 3, image.rgb.data());
    written.push_back(path);
  }
  if (formats.exr) {
    io::ExrImage exr;
    exr.width = image.width;
    exr.height = image.height;
    // The network reproduces the training PNGs' sRGB-encoded values; EXR holds linear light.
    exr.rgb.resize(image.rgb.size());
    io::srgb_to_linear(image.rgb.data(), exr.rgb.data(), image.rgb.size());
    exr.depth = image.depth;
    exr.acc = image.acc;
    exr.attributes = attributes;
    const std::string path = stem + ".exr";
    io::write_exr(path, exr);
    written.push_back(path);
  }
  return written;
}

std::vector<float> error_image(const float* rendered_rgb, const float* truth_rgb, size_t pixels, double gain) {
  std::vector<float> out(3 * pixels);
  for (size_t p = 0; p < pixels; ++p) {
    double sum = 0.0;
    for (int c = 0; c < 3; ++c) sum += std::abs(static_cast<double>(rendered_rgb[3 * p + c]) - truth_rgb[3 * p + c]);
    const float v = static_cast<float>(gain * sum / 3.0);
    out[3 * p] = out[3 * p + 1] = out[3 * p + 2] = v;
  }
  return out;
}

std::vector<std::string> split_image_stems(const data::Split& split) {
  const bool multiscale = split.num_scales() > 1;
  std::vector<std::string> stems;
  size_t view = 0;
  for (size_t i = 0; i < split.num_images(); ++i) {
    if (split.scale_levels[i] == 0 && i > 0) ++view;
    char text[48];
    if (multiscale)
      std::snprintf(text, sizeof(text), "%03zu_scale%u", view, split.scale_levels[i]);
    else
      std::snprintf(text, sizeof(text), "%03zu", view);
    stems.push_back(text);
  }
  return stems;
}

}  // namespace mipnerf::eval
