// Cameras to render that no dataset holds: orbits around a scene, transforms-style camera path files, and
// any camera resized to another resolution with its intrinsics scaled, so the cone radius of every ray
// follows the new pixel size (mip-NeRF's point: one model, any resolution, no aliasing).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "data/pose.hpp"

namespace mipnerf::data {

// Blender's horizontal field of view (camera_angle_x of the lego scene), the default when nothing says otherwise.
constexpr double kDefaultCameraAngleX = 0.6911112070083618;

// A circle of cameras around `target`, all looking at it.
struct OrbitOptions {
  Vec3 target{0.0, 0.0, 0.0};
  Vec3 up{0.0, 0.0, 1.0};          // world up (Blender scenes: +z); need not be unit length
  double radius = 4.0;             // distance of every camera from the target, scene units
  double elevation_deg = 30.0;     // angle above the plane through the target perpendicular to `up`
  double start_azimuth_deg = 0.0;  // azimuth of the first frame (see orbit_cameras)
  uint32_t frames = 120;
  Camera intrinsics;  // size, focal lengths, principal point, near and far of every frame (pose ignored)
};

// Throws mipnerf::Error saying which value is wrong: radius > 0, |elevation| < 90°, frames ≥ 1, a non-zero up,
// finite numbers, and intrinsics with a positive size and focal length.
void validate(const OrbitOptions& options);

// `frames` cameras at azimuths start + 360°·k/frames, k = 0 … frames − 1, at the given elevation and radius, each
// looking at the target with `up` up in the image. Azimuth 0 lies along the world x axis projected onto the plane
// perpendicular to up (y when up is along x); azimuth 90° along up × that axis. With up = +z this is
//   eye = target + radius·(cos e·cos a, cos e·sin a, sin e),
// the convention of the procedural scene's val and test orbits.
std::vector<Camera> orbit_cameras(const OrbitOptions& options);

// An orbit fitted to a capture's cameras: the target is the point closest to every optical axis (the origin when
// the axes are parallel), up is the mean of the cameras' up vectors (+z when they cancel), snapped to a world axis
// when within 20° of one (captures are nearly always axis-aligned; this keeps the orbit level), the radius is the mean
// distance from the cameras to the target, and the intrinsics (size, focal, near/far) are the first camera's.
// Elevation, azimuth and frames keep their defaults. Throws for an empty list.
OrbitOptions orbit_around(const std::vector<Camera>& cameras);

// What a camera path file may leave out.
struct CameraPathDefaults {
  uint32_t width = 0, height = 0;  // the image size when the file gives no w/h (0: then the file must)
  double near = 2.0, far = 6.0;    // when the file gives no near/far
};

// Reads a transforms-style camera path: {"frames": [{"transform_matrix": 4×4 or 3×4 camera-to-world}, ...]} with
// intrinsics as the datasets give them (fl_x, fl_y, cx, cy, w, h, or camera_angle_x/y; global, or per frame
// overriding the global ones; a lens as transforms.json spells it, per frame) and optional near/far (global or per frame). No image is
// read: the size is w × h, else the defaults' size. Poses are validated as the datasets' are. Every problem is
// one mipnerf::Error naming the file and the frame.
std::vector<Camera> read_camera_path(const std::string& path, const CameraPathDefaults& defaults);
// The same from the file's text (`path` names it in errors: `mipnerf-cl view` reads a page's camera this way), or from
// its parsed JSON.
std::vector<Camera> parse_camera_path(const std::string& text, const std::string& path,
                                      const CameraPathDefaults& defaults);
std::vector<Camera> camera_path_from_json(const nlohmann::json& root, const std::string& path,
                                          const CameraPathDefaults& defaults);

// One camera as a camera path's frame, everything read_camera_path reads back: fl_x, fl_y, cx, cy, w, h, near, far,
// transform_matrix and the lens (as transforms.json spells it; none for a pinhole). The one writer of a frame: the
// render command's transforms.json and the viewer's cameras both go through it.
io::Json camera_frame_json(const Camera& camera);

// Writes `cameras` as a camera path read_camera_path accepts (per-frame fl_x, fl_y, cx, cy, w, h, near, far,
// transform_matrix) with each frame's `file_path` (the image rendered from it), atomically.
void write_camera_path(const std::string& path, const std::vector<Camera>& cameras,
                       const std::vector<std::string>& file_paths);

// A requested output resolution: a scale factor, or a width and/or a height in pixels (0 = not given).
struct ResolutionRequest {
  double scale = 0.0;  // > 0: both sides × scale (rounded, at least 1 pixel)
  uint32_t width = 0;  // only width: height follows the aspect ratio (and vice versa)
  uint32_t height = 0;
  bool empty() const { return scale <= 0.0 && width == 0 && height == 0; }
};

// Throws mipnerf::Error for a non-positive or non-finite scale, or a scale given together with a size.
void validate(const ResolutionRequest& request);

// The camera resized to the request. Focal lengths and principal point scale with the pixels (per axis, by the
// ratio of new to old size, as the multiscale pyramid's scale_camera does), so the ray kernel's cone radius —
// proportional to 1/focal — follows the new pixel size. A width and height of another aspect ratio keep square
// pixels: both focal lengths scale with the width, the horizontal field of view is kept, and the vertical one
// is cropped or extended about the principal point. Throws when the result exceeds 2^32 − 1 pixels.
Camera resize_camera(const Camera& camera, const ResolutionRequest& request);

// "WxH" (e.g. "800x600") → {width, height}; throws mipnerf::Error naming `what` for anything else or a zero side.
std::pair<uint32_t, uint32_t> parse_size(const std::string& text, const std::string& what);

}  // namespace mipnerf::data
