// Multiscale Blender: the on-disk builder (its parser is formats/multiscale_blender_parse.cpp, beside its row).
#include "data/multiscale.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/error.hpp"
#include "data/formats/formats.hpp"
#include "data/frames.hpp"
#include "io/file.hpp"
#include "io/png.hpp"

namespace mipnerf::data {
namespace fs = std::filesystem;


namespace {

// The pinhole inverse the official loader reads: pixel (x, y, 1) → camera-frame direction.
io::Json pix2cam_json(const Camera& c) {
  return {{1.0 / c.focal_x_px, 0.0, -c.center_x_px / c.focal_x_px},
          {0.0, -1.0 / c.focal_y_px, c.center_y_px / c.focal_y_px},
          {0.0, 0.0, -1.0}};
}

void write_level_png(const std::string& path, const RgbaImage& image, int bit_depth) {
  io::write_png(path, image.width, image.height, 4, image.rgba.data(), bit_depth);
}

}  // namespace

void write_multiscale(const std::string& in_path, const std::string& out_dir, int scales, const LogFn& log) {
  if (scales < 1 || scales > 8) throw Error("make-multiscale: --scales must be 1 to 8, got " + std::to_string(scales));
  const FormatReader& reader = detect_reader(in_path);
  if (reader.scales_on_disk) {
    throw Error(in_path + ": is already a multiscale dataset (metadata.json); give the full-resolution Blender folder");
  }
  if (!reader.pyramid_source) {
    throw Error(in_path + ": is an " + reader.name + " dataset; make-multiscale builds the paper's pyramid from a "
                "Blender folder or a transforms.json (train builds it on the fly for any format: --set multiscale=true)");
  }
  std::error_code ec;
  if (fs::exists(out_dir) && fs::equivalent(fs::path(in_path), fs::path(out_dir), ec)) {
    throw Error(out_dir + ": the output folder must differ from the input folder");
  }
  LoadOptions options;
  options.log = log;
  const auto splits = reader.parse(in_path, options);
  io::make_directories(out_dir);
  const uint32_t divisor = 1u << (scales - 1);
  io::Json metadata = io::Json::object();
  for (const auto& split : splits) {
    const std::string image_dir = "images_" + split.name;
    io::Json file_path = io::Json::array(), cam2world = io::Json::array(), width = io::Json::array(),
             height = io::Json::array(), focal = io::Json::array(), label = io::Json::array(),
             near = io::Json::array(), far = io::Json::array(), lossmult = io::Json::array(),
             pix2cam = io::Json::array();
    detail::SizeCheck sizes;
    for (size_t i = 0; i < split.frames.size(); ++i) {
      const auto& frame = split.frames[i];
      RgbaImage image = load_rgba_image(frame.image_path);  // PNG or JPEG
      if (split.uniform_size) sizes.check(image.width, image.height, frame.image_path);
      if (image.width % divisor != 0 || image.height % divisor != 0) {
        throw Error(frame.image_path + ": " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                    " is not divisible by " + std::to_string(divisor) + " for " + std::to_string(scales) +
                    " scales; crop the images or use fewer --scales");
      }
      Camera camera;
      camera.camera_to_world = frame.camera_to_world;
      resolve_intrinsics(frame.intrinsics, image.width, image.height, camera, frame.where);
      camera.near = frame.near;
      camera.far = frame.far;
      const int bit_depth = image.bit_depth;
      RgbaImage level_image = std::move(image);
      for (int j = 0; j < scales; ++j) {
        if (j > 0) level_image = downsample2(level_image);
        const Camera level_camera = scale_camera(camera, 1u << j);
        char name[64];
        std::snprintf(name, sizeof(name), "%03zu_d%d.png", i, j);
        const std::string relative = image_dir + "/" + name;
        write_level_png(detail::join_path(out_dir, relative), level_image, bit_depth);
        file_path.push_back(relative);
        cam2world.push_back(pose_to_json(level_camera.camera_to_world));
        width.push_back(level_camera.width_px);
        height.push_back(level_camera.height_px);
        focal.push_back(level_camera.focal_x_px);
        label.push_back(j);
        near.push_back(level_camera.near);
        far.push_back(level_camera.far);
        lossmult.push_back(level_camera.lossmult);
        pix2cam.push_back(pix2cam_json(level_camera));
      }
    }
    metadata[split.name] = {{"file_path", file_path}, {"cam2world", cam2world}, {"width", width},
                            {"height", height},       {"focal", focal},         {"label", label},
                            {"near", near},           {"far", far},             {"lossmult", lossmult},
                            {"pix2cam", pix2cam}};
    if (log) {
      log(LogLevel::info, split.name + ": " + std::to_string(split.frames.size()) + " images x " +
                              std::to_string(scales) + " scales written to " + detail::join_path(out_dir, image_dir));
    }
  }
  // Written last: a dataset folder without metadata.json is visibly incomplete.
  io::write_json(detail::join_path(out_dir, "metadata.json"), metadata, 1);
}

}  // namespace mipnerf::data
