// Orbits, camera path files and resized cameras.
#include "data/paths/camera_path.hpp"

#include <cmath>
#include <cstdio>
#include <limits>

#include "core/error.hpp"
#include "data/intrinsics.hpp"
#include "io/json.hpp"

namespace mipnerf::data {
namespace {

constexpr double kDegree = M_PI / 180.0;
constexpr double kSnapDegrees = 20.0;  // orbit_around: an estimated up this close to a world axis is that axis


std::string number_text(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", v);
  return text;
}

void check_intrinsics(const Camera& c, const std::string& what) {
  if (c.width_px == 0 || c.height_px == 0) throw Error(what + ": the image size must be at least 1x1");
  if (!(c.focal_x_px > 0.0) || !(c.focal_y_px > 0.0) || !std::isfinite(c.focal_x_px) || !std::isfinite(c.focal_y_px)) {
    throw Error(what + ": focal lengths must be positive and finite");
  }
  if (!(c.near >= 0.0) || !(c.far > c.near) || !std::isfinite(c.far)) {
    throw Error(what + ": near and far must satisfy 0 <= near < far, got near " + number_text(c.near) + ", far " +
                number_text(c.far));
  }
}

// The near/far of a path frame: the frame's, else the file's, else the defaults.
double range_value(const io::Json& frame, const io::Json& root, const char* key, double fallback,
                   const std::string& where, const std::string& file) {
  if (const auto v = io::optional_number(frame, key, where)) return *v;
  if (const auto v = io::optional_number(root, key, file)) return *v;
  return fallback;
}

uint32_t size_value(const std::optional<double>& declared, uint32_t fallback, const char* key,
                    const std::string& where) {
  if (declared) {
    if (*declared > static_cast<double>(std::numeric_limits<uint32_t>::max())) {
      throw Error(where + ": '" + key + "' = " + number_text(*declared) + " is too large");
    }
    return static_cast<uint32_t>(std::lround(*declared));
  }
  if (fallback == 0) {
    throw Error(where +
                ": no image size: give 'w' and 'h' (for the file or per frame), or the size to render "
                "(mipnerf-cl render --size WxH)");
  }
  return fallback;
}

}  // namespace

void validate(const OrbitOptions& o) {
  if (!is_finite(o.target)) throw Error("orbit: the target must be finite");
  if (!is_finite(o.up) || !(length(o.up) > 0.0)) throw Error("orbit: the up vector must be finite and non-zero");
  if (!(o.radius > 0.0) || !std::isfinite(o.radius)) {
    throw Error("orbit: the radius must be positive, got " + number_text(o.radius));
  }
  if (!(std::abs(o.elevation_deg) < 90.0)) {
    throw Error("orbit: the elevation must lie strictly between -90 and 90 degrees, got " +
                number_text(o.elevation_deg) + " (at +-90 the view direction is parallel to up)");
  }
  if (!std::isfinite(o.start_azimuth_deg)) throw Error("orbit: the start azimuth must be finite");
  if (o.frames == 0) throw Error("orbit: the number of frames must be at least 1");
  check_intrinsics(o.intrinsics, "orbit");
}

std::vector<Camera> orbit_cameras(const OrbitOptions& o) {
  validate(o);
  const Vec3 up = scale(o.up, 1.0 / length(o.up));
  // Azimuth 0: world x projected onto the orbit's plane (y when up is nearly along x).
  Vec3 reference{1.0, 0.0, 0.0};
  if (std::abs(dot(reference, up)) > 0.9) reference = {0.0, 1.0, 0.0};
  Vec3 e1{reference[0] - dot(reference, up) * up[0], reference[1] - dot(reference, up) * up[1],
          reference[2] - dot(reference, up) * up[2]};
  e1 = scale(e1, 1.0 / length(e1));
  const Vec3 e2 = cross(up, e1);
  const double elevation = o.elevation_deg * kDegree;
  std::vector<Camera> cameras;
  for (uint32_t k = 0; k < o.frames; ++k) {
    const double azimuth = o.start_azimuth_deg * kDegree + 2.0 * M_PI * k / o.frames;
    const double a = std::cos(elevation) * std::cos(azimuth), b = std::cos(elevation) * std::sin(azimuth),
                 c = std::sin(elevation);
    Vec3 eye;
    for (int i = 0; i < 3; ++i) eye[i] = o.target[i] + o.radius * (a * e1[i] + b * e2[i] + c * up[i]);
    Camera camera = o.intrinsics;
    camera.camera_to_world = look_at_pose(eye, o.target, up);
    cameras.push_back(camera);
  }
  return cameras;
}

OrbitOptions orbit_around(const std::vector<Camera>& cameras) {
  if (cameras.empty()) throw Error("orbit: no cameras to fit an orbit to");
  OrbitOptions o;
  o.target = closest_point_to_axes(cameras).value_or(Vec3{0.0, 0.0, 0.0});
  Vec3 up{0.0, 0.0, 0.0};
  double radius = 0.0;
  for (const auto& camera : cameras) {
    const auto& m = camera.camera_to_world;
    for (int i = 0; i < 3; ++i) up[i] += m[i * 4 + 1];  // y_camera in world: the image's up
    const Vec3 centre = camera_center(camera);
    radius += length({centre[0] - o.target[0], centre[1] - o.target[1], centre[2] - o.target[2]});
  }
  // Cameras all around an object tilt their up vectors towards it; the horizontal parts cancel on average, but
  // only roughly for a few random views. Captures are nearly always axis-aligned (Blender: +z up, LLFF: +y), so a
  // mean within kSnapDegrees of a world axis is taken to be that axis: the orbit then stays level.
  if (length(up) > 1e-6 * static_cast<double>(cameras.size())) {
    o.up = scale(up, 1.0 / length(up));
    for (int axis = 0; axis < 3; ++axis) {
      if (std::abs(o.up[axis]) >= std::cos(kSnapDegrees * kDegree)) {
        Vec3 snapped{0.0, 0.0, 0.0};
        snapped[axis] = o.up[axis] > 0 ? 1.0 : -1.0;
        o.up = snapped;
      }
    }
  }
  if (radius > 0.0) o.radius = radius / static_cast<double>(cameras.size());
  o.intrinsics = cameras.front();
  return o;
}

std::vector<Camera> read_camera_path(const std::string& path, const CameraPathDefaults& defaults) {
  return camera_path_from_json(io::read_json(path), path, defaults);
}

std::vector<Camera> parse_camera_path(const std::string& text, const std::string& path,
                                      const CameraPathDefaults& defaults) {
  return camera_path_from_json(io::parse_json(text, path), path, defaults);
}

std::vector<Camera> camera_path_from_json(const nlohmann::json& root, const std::string& path,
                                          const CameraPathDefaults& defaults) {
  io::require_object(root, path);
  const IntrinsicsSpec global = read_intrinsics(root, {}, path);
  const io::Json& frames = io::require_array(root, "frames", path);
  if (frames.empty()) throw Error(path + ": 'frames' is empty: a camera path needs at least one frame");
  std::vector<Camera> cameras;
  for (size_t i = 0; i < frames.size(); ++i) {
    const std::string where = path + ": frames[" + std::to_string(i) + "]";
    const io::Json& frame = io::require_object(frames[i], where);
    const IntrinsicsSpec spec = read_intrinsics(frame, global, where);
    Camera camera;
    camera.camera_to_world = pose_from_json(io::require_key(frame, "transform_matrix", where), where);
    const uint32_t width = size_value(spec.width_px, defaults.width, "w", where);
    const uint32_t height = size_value(spec.height_px, defaults.height, "h", where);
    resolve_intrinsics(spec, width, height, camera, where);
    camera.near = range_value(frame, root, "near", defaults.near, where, path);
    camera.far = range_value(frame, root, "far", defaults.far, where, path);
    check_intrinsics(camera, where);
    cameras.push_back(camera);
  }
  return cameras;
}

io::Json camera_frame_json(const Camera& c) {
  io::Json frame = intrinsics_json(c);  // with the lens: a camera behind a lens renders through it again
  frame["near"] = c.near;
  frame["far"] = c.far;
  frame["transform_matrix"] = pose_to_json(c.camera_to_world);
  return frame;
}

void write_camera_path(const std::string& path, const std::vector<Camera>& cameras,
                       const std::vector<std::string>& file_paths) {
  if (file_paths.size() != cameras.size()) throw Error(path + ": one file path per camera is needed");
  io::Json frames = io::Json::array();
  for (size_t i = 0; i < cameras.size(); ++i) {
    io::Json frame = camera_frame_json(cameras[i]);
    frame["file_path"] = file_paths[i];
    frames.push_back(std::move(frame));
  }
  io::Json root = io::Json::object();
  root["generator"] = "mipnerf-cl render";
  root["frames"] = std::move(frames);
  io::write_json(path, root);
}

void validate(const ResolutionRequest& r) {
  if (r.scale != 0.0 && (!(r.scale > 0.0) || !std::isfinite(r.scale))) {
    throw Error("the scale factor must be positive, got " + number_text(r.scale));
  }
  if (r.scale > 0.0 && (r.width != 0 || r.height != 0)) {
    throw Error("give a scale factor or a size (width, height), not both");
  }
}

Camera resize_camera(const Camera& camera, const ResolutionRequest& r) {
  validate(r);
  if (r.empty()) return camera;
  const double w = camera.width_px, h = camera.height_px;
  auto rounded = [](double v) { return v < 1.0 ? 1.0 : std::round(v); };
  double new_w = 0.0, new_h = 0.0;
  if (r.scale > 0.0) {
    new_w = rounded(w * r.scale);
    new_h = rounded(h * r.scale);
  } else if (r.width != 0 && r.height != 0) {
    new_w = r.width;
    new_h = r.height;
  } else if (r.width != 0) {
    new_w = r.width;
    new_h = rounded(h * r.width / w);
  } else {
    new_h = r.height;
    new_w = rounded(w * r.height / h);
  }
  if (new_w * new_h > static_cast<double>(std::numeric_limits<uint32_t>::max())) {
    throw Error("an image of " + number_text(new_w) + "x" + number_text(new_h) +
                " has more than 2^32 - 1 pixels (pixel ids are 32-bit): render a smaller size or scale");
  }
  const double sx = new_w / w, sy = new_h / h;
  Camera out = camera;
  out.width_px = static_cast<uint32_t>(new_w);
  out.height_px = static_cast<uint32_t>(new_h);
  const bool explicit_both = r.scale <= 0.0 && r.width != 0 && r.height != 0;
  if (explicit_both && std::abs(h * sx - new_h) > 0.5) {
    // Another aspect ratio: square pixels, the horizontal field of view kept, the vertical one cropped or
    // extended about the principal point.
    out.focal_x_px = camera.focal_x_px * sx;
    out.focal_y_px = camera.focal_y_px * sx;
    out.center_x_px = camera.center_x_px * sx;
    out.center_y_px = camera.center_y_px * sx + 0.5 * (new_h - h * sx);
    out.lossmult = camera.lossmult / (sx * sx);
  } else {
    out.focal_x_px = camera.focal_x_px * sx;
    out.focal_y_px = camera.focal_y_px * sy;
    out.center_x_px = camera.center_x_px * sx;
    out.center_y_px = camera.center_y_px * sy;
    out.lossmult = camera.lossmult / (sx * sy);  // the pixel's area in the original pixels
  }
  return out;
}

std::pair<uint32_t, uint32_t> parse_size(const std::string& text, const std::string& what) {
  const std::string expected = what + " '" + text + "': expected WIDTHxHEIGHT in pixels, e.g. 800x600";
  const auto x = text.find_first_of("xX");
  if (x == std::string::npos || x == 0 || x + 1 == text.size()) throw Error(expected);
  auto number = [&](const std::string& part) {
    if (part.size() > 9 || part.find_first_not_of("0123456789") != std::string::npos) throw Error(expected);
    const unsigned long v = std::stoul(part);
    if (v == 0) throw Error(what + " '" + text + "': width and height must be at least 1 pixel");
    return static_cast<uint32_t>(v);
  };
  return {number(text.substr(0, x)), number(text.substr(x + 1))};
}

}  // namespace mipnerf::data
