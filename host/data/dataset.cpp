// Dataset format detection and loading: parse the file's frames, then read, check, (downsample,)
// composite and pack every image of each split.
#include "data/dataset.hpp"

#include <array>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>

#include "core/error.hpp"
#include "data/formats/formats.hpp"
#include "data/frames.hpp"
#include "data/lens_tables.hpp"

namespace mipnerf::data {
namespace fs = std::filesystem;

const char* format_name(DatasetFormat format) { return format_reader(format).name; }

int Split::num_scales() const {
  uint32_t top = 0;
  for (uint32_t level : scale_levels) top = std::max(top, level);
  return cameras.empty() ? 0 : static_cast<int>(top) + 1;
}

bool Dataset::has_split(const std::string& name) const {
  for (const auto& s : splits) {
    if (s.name == name) return true;
  }
  return false;
}

std::string Dataset::split_names() const {
  std::string names;
  for (const auto& s : splits) names += (names.empty() ? "" : ", ") + s.name;
  return names.empty() ? "none" : names;
}

const Split& Dataset::split(const std::string& name) const {
  for (const auto& s : splits) {
    if (s.name == name) return s;
  }
  throw Error(path + ": no split '" + name + "' (this dataset has: " + split_names() + ")");
}


Camera camera_at_factor(const Camera& camera, uint32_t factor) {
  if (factor <= 1) return camera;
  if (camera.width_px < factor || camera.height_px < factor) {
    throw Error("camera_at_factor: " + std::to_string(camera.width_px) + "x" + std::to_string(camera.height_px) +
                " is smaller than factor " + std::to_string(factor));
  }
  Camera cropped = camera;
  cropped.width_px -= camera.width_px % factor;
  cropped.height_px -= camera.height_px % factor;
  return scale_camera(cropped, factor);
}

Camera scale_camera(const Camera& camera, uint32_t factor) {
  if (factor == 1) return camera;
  if (camera.width_px % factor != 0 || camera.height_px % factor != 0) {
    throw Error("scale_camera: " + std::to_string(camera.width_px) + "x" + std::to_string(camera.height_px) +
                " is not divisible by " + std::to_string(factor));
  }
  Camera scaled = camera;
  const double f = factor;
  scaled.focal_x_px /= f;
  scaled.focal_y_px /= f;
  scaled.center_x_px /= f;  // pixel k of the smaller image covers pixels [f·k, f·k + f) of the larger
  scaled.center_y_px /= f;
  scaled.width_px /= factor;
  scaled.height_px /= factor;
  scaled.lossmult *= f * f;
  return scaled;
}

void append_image(Split& split, const RgbaImage& image, const Camera& camera, uint32_t base_level, int scales,
                  Background background, const std::string& file) {
  if (scales < 1 || scales > 8) throw Error("the number of scales must be 1 to 8, got " + std::to_string(scales));
  const uint32_t divisor = 1u << (scales - 1);
  if (image.width % divisor != 0 || image.height % divisor != 0) {
    throw Error(file + ": " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                " is not divisible by " + std::to_string(divisor) + " for " + std::to_string(scales) +
                " scales; crop the images or use fewer scales");
  }
  RgbaImage smaller;
  const RgbaImage* level_image = &image;
  for (int j = 0; j < scales; ++j) {
    if (j > 0) {
      smaller = downsample2(*level_image);
      level_image = &smaller;
    }
    const Camera level_camera = scale_camera(camera, 1u << j);
    const uint64_t pixels = static_cast<uint64_t>(level_image->width) * level_image->height;
    const uint64_t offset = split.pixel_offsets.back();
    split.rgb.resize(3 * (offset + pixels));
    composite(*level_image, background, split.rgb.data() + 3 * offset);
    split.pixel_offsets.push_back(offset + pixels);
    split.cameras.push_back(level_camera);
    split.scale_levels.push_back(base_level + j);
    split.files.push_back(file);
  }
}

namespace detail {

void SizeCheck::check(uint32_t width, uint32_t height, const std::string& file) {
  if (first_file_.empty()) {
    width_ = width;
    height_ = height;
    first_file_ = file;
    return;
  }
  if (width != width_ || height != height_) {
    throw Error(file + ": the image is " + std::to_string(width) + "x" + std::to_string(height) + " but " +
                first_file_ + " is " + std::to_string(width_) + "x" + std::to_string(height_) +
                "; every image of a Blender split must have the same size (resize or re-render it)");
  }
}

}  // namespace detail

namespace {

// check_lens_over_image once per distinct lens, intrinsics and size (a capture's frames usually share one camera).
class LensCheck {
 public:
  void check(const Camera& camera, const std::string& where) {
    if (camera.lens.is_pinhole()) return;
    const Lens& l = camera.lens;
    const std::vector<double> key = {static_cast<double>(l.model), l.k1, l.k2, l.k3, l.k4, l.p1, l.p2,
                                     camera.focal_x_px, camera.focal_y_px, camera.center_x_px, camera.center_y_px,
                                     static_cast<double>(camera.width_px), static_cast<double>(camera.height_px)};
    if (checked_.insert(key).second) check_lens_over_image(camera, where);
  }

 private:
  std::set<std::vector<double>> checked_;
};

// NDC is the frustum of one camera: the ray kernel maps each camera's rays through its own focal length and principal
// point per image size, so a second projection would put the same world point elsewhere in NDC. Throws naming the
// frame that differs from the first (LoadOptions::forward_facing_ndc).
class ProjectionCheck {
 public:
  void check(const Camera& camera, const std::string& where) {
    const std::array<double, 4> projection = {camera.focal_x_px / camera.width_px, camera.focal_y_px / camera.height_px,
                                              camera.center_x_px / camera.width_px,
                                              camera.center_y_px / camera.height_px};
    if (first_where_.empty()) {
      first_ = projection;
      first_where_ = where;
      return;
    }
    for (size_t k = 0; k < projection.size(); ++k) {
      if (std::abs(projection[k] - first_[k]) > 1e-6 * std::abs(first_[k])) {
        throw Error(where + ": its focal length or principal point, per image size, differs from " + first_where_ +
                    "'s: NDC rays (ray_shape = cylinder) map one camera's frustum, so a capture of several cameras "
                    "trains with --set ray_shape=cone");
      }
    }
  }

 private:
  std::array<double, 4> first_{};
  std::string first_where_;
};

// "1 row", "3 rows", "0 rows".
std::string count_of(uint32_t n, const std::string& noun) {
  return std::to_string(n) + " " + noun + (n == 1 ? "" : "s");
}

Split load_split(const detail::SplitSpec& spec, const LoadOptions& options) {
  Split split;
  split.name = spec.name;
  split.source = spec.source;
  detail::SizeCheck sizes;
  LensCheck lenses;
  ProjectionCheck projections;
  // A size the factor does not divide is cropped at its right and bottom edges to the largest size it divides, then
  // box-downsampled: pixel k still covers source pixels [f·k, f·k + f), so the intrinsics (focal, principal point, lens)
  // stay exact. The official LLFF loader reads ImageMagick's minified copies instead (`mogrify -resize 25%`: 800x533 →
  // 200x133, sizes rounded, the whole image rescaled by 200/800 and 133/533 while the intrinsics are divided by 4);
  // both give floor(W/f) x floor(H/f) when the remainder is under f/2, ours without the small scale error.
  bool cropped_note_given = false;
  for (const auto& frame : spec.frames) {
    RgbaImage image = load_rgba_image(frame.image_path);
    if (spec.uniform_size) sizes.check(image.width, image.height, frame.image_path);
    Camera camera;
    camera.camera_to_world = frame.camera_to_world;
    resolve_intrinsics(frame.intrinsics, image.width, image.height, camera, frame.where);
    lenses.check(camera, frame.where);
    const uint32_t factor = std::max<uint32_t>(1, options.factor / frame.stored_factor);
    if (factor > 1) {
      if (image.width % factor != 0 || image.height % factor != 0) {
        const uint32_t cropped_width = image.width - image.width % factor;
        const uint32_t cropped_height = image.height - image.height % factor;
        if (cropped_width == 0 || cropped_height == 0) {
          throw Error(frame.image_path + ": " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                      " is smaller than factor " + std::to_string(factor) + "; use a smaller factor");
        }
        if (!cropped_note_given && options.log) {
          options.log(LogLevel::warning,
                      frame.image_path + ": " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                          " is not divisible by factor " + std::to_string(factor) + ": its last " +
                          count_of(image.width - cropped_width, "column") + " and " +
                          count_of(image.height - cropped_height, "row") + " are dropped, and it trains at " +
                          std::to_string(cropped_width / factor) + "x" + std::to_string(cropped_height / factor) +
                          " (so are the split's other images of this size)");
          cropped_note_given = true;
        }
        image = crop_top_left(image, cropped_width, cropped_height);
      }
      for (uint32_t f = 1; f < factor; f *= 2) image = downsample2(image);
      camera = camera_at_factor(camera, factor);
    }
    if (options.forward_facing_ndc) projections.check(camera, frame.where);
    camera.near = frame.near;
    camera.far = frame.far;
    camera.lossmult = frame.lossmult;
    if (split.rgb.empty()) {
      // Reserve for the whole split from the first image (every level adds a quarter of the one before).
      const double pyramid = (1.0 - std::pow(0.25, options.scales)) / 0.75;
      split.rgb.reserve(static_cast<size_t>(3.0 * image.width * image.height * spec.frames.size() * pyramid) + 3);
    }
    append_image(split, image, camera, frame.scale_level, options.scales, options.background, frame.image_path);
  }
  return split;
}

}  // namespace

Dataset load_dataset(const std::string& path, const LoadOptions& options) {
  if (options.scales < 1 || options.scales > 8) {
    throw Error("the number of scales must be 1 to 8 (the paper's multiscale Blender uses 4), got " +
                std::to_string(options.scales));
  }
  if (options.factor < 1 || (options.factor & (options.factor - 1)) != 0 || options.factor > 64) {
    throw Error("the downsampling factor must be a power of two from 1 to 64, got " + std::to_string(options.factor));
  }
  const FormatReader& reader = detect_reader(path);
  Dataset dataset;
  dataset.path = path;
  dataset.format = reader.format;
  dataset.background = options.background;
  const std::vector<detail::SplitSpec> specs = reader.parse(path, options);
  if (specs.empty()) throw Error(path + ": the dataset has none of the requested splits");
  for (const auto& spec : specs) dataset.splits.push_back(load_split(spec, options));
  return dataset;
}

}  // namespace mipnerf::data
