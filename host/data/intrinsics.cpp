// Reading and resolving pinhole intrinsics.
#include "data/intrinsics.hpp"

#include <cmath>

#include "core/error.hpp"

namespace mipnerf::data {
namespace {

void read_positive(const io::Json& object, const char* key, std::optional<double>& out, const std::string& where) {
  const auto value = io::optional_number(object, key, where);
  if (!value) return;
  if (!(*value > 0.0)) throw Error(where + ": '" + key + "' must be positive, got " + std::to_string(*value));
  out = value;
}

void read_center(const io::Json& object, const char* key, std::optional<double>& out, const std::string& where) {
  const auto value = io::optional_number(object, key, where);
  if (value) out = value;
}

void refuse_distortion(const io::Json& object, const std::string& where) {
  static const char* const kDistortionKeys[] = {"k1", "k2", "k3", "k4", "k5", "k6", "p1", "p2"};
  for (const char* key : kDistortionKeys) {
    const auto value = io::optional_number(object, key, where);
    if (value && *value != 0.0) {
      throw Error(where + ": lens distortion " + key + " = " + std::to_string(*value) +
                  " is not supported (pinhole cameras only): undistort the images first (e.g. COLMAP's "
                  "image_undistorter) and remove the distortion keys");
    }
  }
  if (object.contains("camera_model") && object.at("camera_model").is_string()) {
    const std::string model = object.at("camera_model").get<std::string>();
    if (model.find("FISHEYE") != std::string::npos || model.find("fisheye") != std::string::npos ||
        model == "EQUIRECTANGULAR") {
      throw Error(where + ": camera_model '" + model +
                  "' is not supported (pinhole cameras only): undistort the images to a pinhole camera first");
    }
  }
}

}  // namespace

IntrinsicsSpec read_intrinsics(const io::Json& object, const IntrinsicsSpec& base, const std::string& where) {
  io::require_object(object, where);
  refuse_distortion(object, where);
  IntrinsicsSpec spec = base;
  read_positive(object, "fl_x", spec.focal_x_px, where);
  read_positive(object, "fl_y", spec.focal_y_px, where);
  read_center(object, "cx", spec.center_x_px, where);
  read_center(object, "cy", spec.center_y_px, where);
  read_positive(object, "w", spec.width_px, where);
  read_positive(object, "h", spec.height_px, where);
  read_positive(object, "camera_angle_x", spec.camera_angle_x, where);
  read_positive(object, "camera_angle_y", spec.camera_angle_y, where);
  for (const auto* angle : {&spec.camera_angle_x, &spec.camera_angle_y}) {
    if (*angle && **angle >= M_PI) {
      throw Error(where + ": camera_angle_x/y must be a field of view in radians below pi, got " +
                  std::to_string(**angle));
    }
  }
  return spec;
}

void resolve_intrinsics(const IntrinsicsSpec& spec, uint32_t width, uint32_t height, Camera& camera,
                        const std::string& where) {
  const std::string size = std::to_string(width) + "x" + std::to_string(height);
  if ((spec.width_px && std::abs(*spec.width_px - width) > 0.5) ||
      (spec.height_px && std::abs(*spec.height_px - height) > 0.5)) {
    const std::string declared = (spec.width_px ? std::to_string(std::lround(*spec.width_px)) : "?") + "x" +
                                 (spec.height_px ? std::to_string(std::lround(*spec.height_px)) : "?");
    throw Error(where + ": the image is " + size + " but w/h say " + declared +
                "; the intrinsics must describe the image as stored (rescale fl_x, fl_y, cx, cy with it)");
  }
  if (spec.focal_x_px) {
    camera.focal_x_px = *spec.focal_x_px;
  } else if (spec.camera_angle_x) {
    camera.focal_x_px = 0.5 * width / std::tan(0.5 * *spec.camera_angle_x);
  } else {
    throw Error(where + ": no focal length: give 'fl_x' (pixels) or 'camera_angle_x' (radians)");
  }
  if (spec.focal_y_px) {
    camera.focal_y_px = *spec.focal_y_px;
  } else if (spec.camera_angle_y && !spec.focal_x_px) {
    camera.focal_y_px = 0.5 * height / std::tan(0.5 * *spec.camera_angle_y);
  } else {
    camera.focal_y_px = camera.focal_x_px;
  }
  camera.center_x_px = spec.center_x_px.value_or(0.5 * width);
  camera.center_y_px = spec.center_y_px.value_or(0.5 * height);
  camera.width_px = width;
  camera.height_px = height;
}

}  // namespace mipnerf::data
