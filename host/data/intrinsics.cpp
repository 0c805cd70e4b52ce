// Reading and resolving intrinsics: pinhole cameras, and the lenses of core/lens.hpp.
#include "data/intrinsics.hpp"

#include <cmath>

#include "core/error.hpp"
#include "core/lens_models.hpp"

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

// The model name a transforms object gives: "camera_model", or instant-ngp's "is_fisheye" (OPENCV_FISHEYE), or
// plain coefficients (OPENCV, instant-ngp's k1, k2, p1, p2), or none of them (PINHOLE).
std::string lens_model_named(const io::Json& object, const std::string& where) {
  if (object.contains("camera_model")) {
    if (!object.at("camera_model").is_string()) throw Error(where + ": 'camera_model' must be a string");
    return object.at("camera_model").get<std::string>();
  }
  if (object.contains("is_fisheye") && object.at("is_fisheye").is_boolean() && object.at("is_fisheye").get<bool>()) {
    return lens_model_name(LensModel::opencv_fisheye);
  }
  for (const auto& name : lens_coefficient_names()) {
    if (object.contains(name) && coefficient(object, name.c_str(), where) != 0.0) {
      return lens_model_name(LensModel::opencv);
    }
  }
  return lens_model_name(LensModel::pinhole);
}

// The lens a transforms file describes, as nerfstudio writes it ("camera_model" with the coefficients its row takes,
// core/lens_models.hpp) or instant-ngp ("is_fisheye", or plain k1, k2, p1, p2 meaning OPENCV); nothing when the
// object says nothing about a lens (the frame then keeps the file's). Throws naming `where` for a model not read here
// and for coefficients the model does not take.
std::optional<Lens> read_lens(const io::Json& object, const std::string& where) {
  bool any_key = object.contains("camera_model") || object.contains("is_fisheye");
  for (const auto& key : lens_coefficient_names()) any_key = any_key || object.contains(key);
  if (!any_key) return std::nullopt;
  const std::string model = lens_model_named(object, where);
  const LensRow* row = find_lens_row(model);
  if (!row) {
    throw Error(where + ": camera_model '" + model + "' is not read: mipnerf-cl reads " + lens_model_list() +
                " cameras; undistort the images to a pinhole camera first (e.g. COLMAP's image_undistorter)");
  }
  std::vector<double> values;
  for (const auto& c : row->coefficients) values.push_back(coefficient(object, c.name, where));
  for (const auto& key : lens_coefficient_names()) {
    if (row->takes(key) || coefficient(object, key.c_str(), where) == 0.0) continue;
    if (row->coefficients.empty()) {
      throw Error(where + ": camera_model " + model + " with distortion coefficients: give the model they belong to "
                  "(e.g. OPENCV)");
    }
    throw Error(where + ": camera_model " + model + " has coefficients it does not take (" + lens_coefficient_list() +
                ")");
  }
  return make_lens(*row, values, where);
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
  const LensRow& row = lens_row(lens.model);
  json["camera_model"] = row.colmap_name;
  for (const auto& c : row.coefficients) json[c.name] = lens.*c.value;
  return json;
}

io::Json intrinsics_json(const Camera& c) {
  io::Json json = {{"fl_x", c.focal_x_px}, {"fl_y", c.focal_y_px}, {"cx", c.center_x_px},
                   {"cy", c.center_y_px},  {"w", c.width_px},     {"h", c.height_px}};
  json.update(lens_json(c.lens));
  return json;
}

}  // namespace mipnerf::data
