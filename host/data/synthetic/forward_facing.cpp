// The forward-facing scene: backdrop, camera grid, LLFF writer.
#include "data/synthetic/forward_facing.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/lens_models.hpp"
#include "data/intrinsics.hpp"
#include "data/lens_tables.hpp"
#include "data/pose.hpp"
#include "io/json.hpp"
#include "data/synthetic/llff_writer.hpp"
#include "data/synthetic/procedural.hpp"

namespace mipnerf::data {
namespace {

constexpr double kWallY = 2.5;     // a wall behind the scene (the cameras look along +y)
constexpr double kFloorZ = -0.7;   // a floor just under the procedural scene's slab
constexpr double kCameraY = -4.0;  // the camera plane

// The procedural scene, else the nearer of the wall (vertical stripes) and the floor (a coarse checker).
SceneHit trace_with_backdrop(const Ray& ray) {
  SceneHit hit = trace_procedural(ray);
  if (hit.hit) return hit;
  const auto& o = ray.origin_world;
  const auto& d = ray.direction_world;
  double best = 1e300;
  auto consider = [&](double t, bool wall) {
    if (!(t > 1e-9 && t < best)) return;
    best = t;
    const double x = o[0] + t * d[0], y = o[1] + t * d[1];
    const bool odd = wall ? (static_cast<int>(std::floor(x / 0.35)) & 1) != 0
                          : ((static_cast<int>(std::floor(x / 0.5)) ^ static_cast<int>(std::floor(y / 0.5))) & 1) != 0;
    const double light = wall ? 0.8 : 0.65;
    hit.hit = true;
    hit.t = t;
    hit.rgb = wall ? std::array<double, 3>{odd ? 0.55 * light : 0.85 * light, 0.5 * light, odd ? 0.35 * light : 0.6 * light}
                   : std::array<double, 3>{odd ? 0.3 : 0.55, odd ? 0.28 : 0.5, odd ? 0.25 : 0.45};
  };
  if (d[1] > 0) consider((kWallY - o[1]) / d[1], true);
  if (d[2] < 0) consider((kFloorZ - o[2]) / d[2], false);
  return hit;
}

// Nearest and farthest depth the camera sees (every ray hits the scene or the backdrop), widened by 10 % as a
// capture's bounds from its sparse points would be.
std::array<double, 2> depth_bounds(const Camera& camera) {
  const std::vector<double> depths = traced_depths(camera, trace_with_backdrop);
  return {0.9 * depths.front(), 1.1 * depths.back()};
}

}  // namespace

void validate(const ForwardFacingOptions& o) {
  const uint32_t divisor = 4 * std::max<uint32_t>(o.factor, 1);  // 4:3 images, then the factor
  if (o.width_px < 8 || o.width_px > 4096 || o.width_px % divisor != 0) {
    throw Error("make-scene --forward-facing: --size must be 8 to 4096 and divisible by " + std::to_string(divisor) +
                " (4:3 images, downsampled by " + std::to_string(o.factor) + "), got " + std::to_string(o.width_px));
  }
  if (o.factor < 1 || o.factor > 16 || (o.factor & (o.factor - 1)) != 0) {
    throw Error("make-scene --forward-facing: --factor must be a power of two from 1 to 16");
  }
  if (o.views_x < 2 || o.views_y < 2 || o.views_x * o.views_y > 400) {
    throw Error("make-scene --forward-facing: the camera grid must be at least 2 x 2 and at most 400 views");
  }
  if (o.samples_per_axis < 1 || o.samples_per_axis > 64) throw Error("make-scene: --samples must be 1 to 64");
  if (!(o.grid_width >= 0.01 && o.grid_width <= 4.0)) {
    throw Error("make-scene --forward-facing: --grid-width must be 0.01 to 4 (scene units; the scene is 4 away)");
  }
  if (!o.lens.is_pinhole()) {
    Camera camera = centred_pinhole(look_at_pose({0, kCameraY, 0.8}, {0, kWallY, 0}, {0, 0, 1}), o.width_px,
                                    o.width_px * 3 / 4, o.camera_angle_x);
    camera.lens = o.lens;
    check_lens_over_image(camera, std::string("make-scene --forward-facing --lens ") + lens_model_name(o.lens.model));
  }
}

std::vector<Camera> forward_facing_cameras(const ForwardFacingOptions& options) {
  validate(options);
  std::vector<Camera> cameras;
  const uint32_t height = options.width_px * 3 / 4;
  for (uint32_t row = 0; row < options.views_y; ++row) {
    for (uint32_t col = 0; col < options.views_x; ++col) {
      // A hand-held grid: 1.2 wide, 0.6 high by default (grid_width), centred at x 0 and z 0.8, axes converging
      // gently on the wall. Written so that the default grid is the one the earlier constants gave, bit for bit.
      const double grid_height = 0.5 * options.grid_width;
      const double x = -0.5 * options.grid_width + options.grid_width * col / (options.views_x - 1);
      const double z = 1.1 - 0.5 * (0.6 - grid_height) - grid_height * row / (options.views_y - 1);
      Camera camera = centred_pinhole(look_at_pose({x, kCameraY, z}, {0.5 * x, kWallY, 0.0}, {0, 0, 1}),
                                      options.width_px, height, options.camera_angle_x);
      camera.lens = options.lens;
      const auto bounds = depth_bounds(camera);
      camera.near = bounds[0];
      camera.far = bounds[1];
      cameras.push_back(camera);
    }
  }
  return cameras;
}

namespace {

// The capture behind a lens as a transforms.json, as `dataset import-colmap` writes one: every view's pose,
// intrinsics and lens, near/far over every view.
void write_lens_transforms(const std::string& out_dir, const std::vector<Camera>& cameras, bool jpeg) {
  io::Json frames = io::Json::array();
  double near = cameras.front().near, far = cameras.front().far;
  for (size_t k = 0; k < cameras.size(); ++k) {
    io::Json frame = intrinsics_json(cameras[k]);
    frame["file_path"] = "images/" + llff_image_name(k, jpeg);
    frame["transform_matrix"] = pose_to_json(cameras[k].camera_to_world);
    frames.push_back(frame);
    near = std::min(near, cameras[k].near);
    far = std::max(far, cameras[k].far);
  }
  io::write_json(out_dir + "/transforms.json", {{"near", near}, {"far", far}, {"frames", frames}});
}

}  // namespace

void write_forward_facing_scene(const std::string& out_dir, const ForwardFacingOptions& options, const LogFn& log) {
  const auto cameras = forward_facing_cameras(options);
  if (options.lens.is_pinhole()) {
    write_llff_views(out_dir, cameras, trace_with_backdrop, llff_write_options(options, 0x46460000u));
  } else {
    // A transforms.json reads images/ only, downsampling on load (--set factor): no images_<factor>/ beside it.
    LlffWriteOptions write = llff_write_options(options, 0x46460000u);
    write.factor = 1;
    write_view_images(out_dir, cameras, trace_with_backdrop, write);
    write_lens_transforms(out_dir, cameras, options.jpeg);
  }
  if (log) {
    log(LogLevel::info, "forward-facing scene: " + std::to_string(cameras.size()) + " views at " +
                            std::to_string(options.width_px) + "x" + std::to_string(cameras[0].height_px) +
                            (options.factor > 1 ? " (and images_" + std::to_string(options.factor) + "/)" : ""));
  }
}

}  // namespace mipnerf::data
