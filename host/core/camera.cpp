// Camera packing and the ray of a pixel (double precision; the ray kernel implements the same math).
#include "core/camera.hpp"

#include <cmath>

namespace mipnerf {

std::vector<float> pack_cameras(const std::vector<Camera>& cameras) {
  namespace L = camera_layout;
  std::vector<float> packed(cameras.size() * L::stride, 0.0f);
  for (std::size_t c = 0; c < cameras.size(); ++c) {
    float* out = packed.data() + c * L::stride;
    const Camera& cam = cameras[c];
    for (int i = 0; i < 12; ++i) out[L::camera_to_world + i] = static_cast<float>(cam.camera_to_world[i]);
    out[L::focal_x] = static_cast<float>(cam.focal_x_px);
    out[L::focal_y] = static_cast<float>(cam.focal_y_px);
    out[L::center_x] = static_cast<float>(cam.center_x_px);
    out[L::center_y] = static_cast<float>(cam.center_y_px);
    out[L::width] = static_cast<float>(cam.width_px);
    out[L::height] = static_cast<float>(cam.height_px);
    out[L::near] = static_cast<float>(cam.near);
    out[L::far] = static_cast<float>(cam.far);
    out[L::lossmult] = static_cast<float>(cam.lossmult);
  }
  return packed;
}

Ray camera_ray(const Camera& camera, double x_px, double y_px) {
  // Normalised coordinates in the lens's (OpenCV) frame: y down.
  Uv uv = {(x_px - camera.center_x_px) / camera.focal_x_px, (y_px - camera.center_y_px) / camera.focal_y_px};
  if (!camera.lens.is_pinhole() && !undistort(camera.lens, uv, uv)) uv = {NAN, NAN};
  const double dir_camera[3] = {uv[0], -uv[1], -1.0};
  const auto& m = camera.camera_to_world;
  Ray ray;
  for (int row = 0; row < 3; ++row) {
    ray.direction_world[row] =
        m[row * 4 + 0] * dir_camera[0] + m[row * 4 + 1] * dir_camera[1] + m[row * 4 + 2] * dir_camera[2];
    ray.origin_world[row] = m[row * 4 + 3];
  }
  return ray;
}

}  // namespace mipnerf
