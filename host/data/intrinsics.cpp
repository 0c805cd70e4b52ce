// Reading and resolving intrinsics: pinhole cameras, and the lenses of core/lens.hpp.
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

// A coefficient of the lens, 0 when absent; must be finite (the JSON reader refuses non-finite numbers).
double coefficient(const io::Json& object, const char* key, const std::string& where) {
  return io::optional_number(object, key, where).value_or(0.0);
}

// The lens a transforms file describes, as nerfstudio writes it ("camera_model": OPENCV, OPENCV_FISHEYE, …, with
// k1..k4, p1, p2) or instant-ngp ("is_fisheye", or plain k1, k2, p1, p2 meaning OPENCV); nothing when the object
// says nothing about a lens (the frame then keeps the file's). Throws naming `where` for a model not read here and
// for coefficients the model does not have.
std::optional<Lens> read_lens(const io::Json& object, const std::string& where) {
  static const char* const kKeys[] = {"k1", "k2", "k3", "k4", "k5", "k6", "p1", "p2"};
  bool any_key = object.contains("camera_model") || object.contains("is_fisheye");
  for (const char* key : kKeys) any_key = any_key || object.contains(key);
  if (!any_key) return std::nullopt;
  Lens lens;
  lens.k1 = coefficient(object, "k1", where);
  lens.k2 = coefficient(object, "k2", where);
  lens.k3 = coefficient(object, "k3", where);
  lens.k4 = coefficient(object, "k4", where);
  lens.p1 = coefficient(object, "p1", where);
  lens.p2 = coefficient(object, "p2", where);
  for (const char* key : {"k5", "k6"}) {
    if (coefficient(object, key, where) != 0.0) {
      throw Error(where + ": lens distortion " + key + " is not read (FULL_OPENCV): mipnerf-cl reads PINHOLE, "
                  "SIMPLE_RADIAL, RADIAL, OPENCV and OPENCV_FISHEYE cameras; undistort the images first");
    }
  }
  std::string model;
  if (object.contains("camera_model")) {
    if (!object.at("camera_model").is_string()) throw Error(where + ": 'camera_model' must be a string");
    model = object.at("camera_model").get<std::string>();
  } else if (object.contains("is_fisheye") && object.at("is_fisheye").is_boolean() && object.at("is_fisheye").get<bool>()) {
    model = "OPENCV_FISHEYE";
  } else {
    model = (lens.k1 || lens.k2 || lens.p1 || lens.p2 || lens.k3 || lens.k4) ? "OPENCV" : "PINHOLE";
  }
  const bool radial_only = lens.p1 == 0 && lens.p2 == 0 && lens.k3 == 0 && lens.k4 == 0;
  if (model == "PINHOLE" || model == "SIMPLE_PINHOLE") {
    if (lens.k1 || lens.k2 || lens.k3 || lens.k4 || lens.p1 || lens.p2) {
      throw Error(where + ": camera_model " + model + " with distortion coefficients: give the model they belong to "
                  "(e.g. OPENCV)");
    }
    lens.model = LensModel::pinhole;
  } else if (model == "SIMPLE_RADIAL" && radial_only && lens.k2 == 0) {
    lens.model = LensModel::simple_radial;
  } else if (model == "RADIAL" && radial_only) {
    lens.model = LensModel::radial;
  } else if (model == "OPENCV" && lens.k3 == 0 && lens.k4 == 0) {
    lens.model = LensModel::opencv;
  } else if (model == "OPENCV_FISHEYE" && lens.p1 == 0 && lens.p2 == 0) {
    lens.model = LensModel::opencv_fisheye;
  } else if (model == "SIMPLE_RADIAL" || model == "RADIAL" || model == "OPENCV" || model == "OPENCV_FISHEYE") {
    throw Error(where + ": camera_model " + model + " has coefficients it does not take (SIMPLE_RADIAL: k1; RADIAL: "
                "k1, k2; OPENCV: k1, k2, p1, p2; OPENCV_FISHEYE: k1..k4)");
  } else {
    throw Error(where + ": camera_model '" + model + "' is not read: mipnerf-cl reads PINHOLE, SIMPLE_RADIAL, RADIAL, "
                "OPENCV and OPENCV_FISHEYE cameras; undistort the images to a pinhole camera first (e.g. COLMAP's "
                "image_undistorter)");
  }
  return lens;
}

}  // namespace

IntrinsicsSpec read_intrinsics(const io::Json& object, const IntrinsicsSpec& base, const std::string& where) {
  io::require_object(object, where);
  IntrinsicsSpec spec = base;
  if (auto lens = read_lens(object, where)) spec.lens = *lens;
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
  camera.lens = spec.lens.value_or(Lens{});
}

io::Json lens_json(const Lens& lens) {
  io::Json json = io::Json::object();
  if (lens.is_pinhole()) return json;
  json["camera_model"] = lens_model_name(lens.model);
  json["k1"] = lens.k1;
  json["k2"] = lens.k2;
  json["k3"] = lens.k3;
  json["k4"] = lens.k4;
  json["p1"] = lens.p1;
  json["p2"] = lens.p2;
  return json;
}

}  // namespace mipnerf::data
