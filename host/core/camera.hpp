// A camera in the Blender/OpenGL convention (a pinhole, or a pinhole behind a lens that distorts: core/lens.hpp),
// its packed device layout, and the ray of a pixel.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/lens.hpp"

namespace mipnerf {

// One image's camera. Axes are OpenGL's: the camera looks down −z_camera, y_camera is up, x_camera
// right; `camera_to_world` maps camera-frame points to world points (Blender's transform_matrix).
struct Camera {
  std::array<double, 12> camera_to_world{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};  // 3×4, row-major
  double focal_x_px = 1.0;    // focal length in pixels, horizontal
  double focal_y_px = 1.0;    // focal length in pixels, vertical
  double center_x_px = 0.5;   // principal point, pixels from the left edge
  double center_y_px = 0.5;   // principal point, pixels from the top edge
  uint32_t width_px = 1;
  uint32_t height_px = 1;
  double near = 2.0;          // sampling range along the ray, in units of t (see camera_ray)
  double far = 6.0;
  double lossmult = 1.0;      // per-pixel loss weight: (full-res pixel area ratio), 1, 4, 16, 64 for multiscale
  Lens lens;                  // distortion on normalised coordinates (pinhole: none); resizing keeps it
};

// Packed float layout of a camera on the device: kernels/common.cl defines the same offsets
// (CAMERA_*); tests/data checks that the two agree.
namespace camera_layout {
constexpr int camera_to_world = 0;  // 12 floats, row-major 3×4
constexpr int focal_x = 12;
constexpr int focal_y = 13;
constexpr int center_x = 14;
constexpr int center_y = 15;
constexpr int width = 16;
constexpr int height = 17;
constexpr int near = 18;
constexpr int far = 19;
constexpr int lossmult = 20;
// The camera's lens table (data/lens_tables.hpp) as the bits of a uint, offset + 1 in the tables' float4 elements;
// 0 (pack_cameras' value): no table, the pinhole formula.
constexpr int lens_table = 21;
constexpr int stride = 24;  // floats per camera (22, 23 reserved, zero)
}  // namespace camera_layout

// cameras [C][camera_layout::stride], as uploaded for the ray kernel.
std::vector<float> pack_cameras(const std::vector<Camera>& cameras);

struct Ray {
  std::array<double, 3> origin_world;
  std::array<double, 3> direction_world;  // unnormalised: the camera-frame direction has z = −1
};

// The ray through image position (x_px, y_px), measured in pixels from the top-left corner, so the
// centre of pixel (i, j) is (i + 0.5, j + 0.5). The camera-frame direction is
// ((x − cx)/fx, −(y − cy)/fy, −1), the official mip-NeRF/NeRF convention: t = 1 is one unit of depth
// in front of the camera, so near and far are depths along the optical axis. Behind a lens, ((x − cx)/fx,
// (y − cy)/fy) is first undistorted (core/lens.hpp) to (u, v), and the direction is (u, −v, −1); NaN where the lens
// cannot be inverted.
Ray camera_ray(const Camera& camera, double x_px, double y_px);

}  // namespace mipnerf
