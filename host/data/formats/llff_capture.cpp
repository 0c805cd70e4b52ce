// LLFF captures: poses_bounds.npy, the official transformations, splits and the render path.
#include "data/formats/llff_capture.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/error.hpp"
#include "data/frames.hpp"
#include "data/image.hpp"
#include "io/npy.hpp"

namespace mipnerf::data {
namespace fs = std::filesystem;
namespace {

// The official _generate_spherical_poses, the re-posing part: centre on the point nearest every optical axis, z
// up along the mean offset of the cameras from it, unit mean distance. Bounds scale with the poses.
void spherify(std::vector<Matrix34>& poses, std::vector<std::array<double, 2>>& bounds, const std::string& where) {
  std::vector<Camera> cameras(poses.size());
  for (size_t i = 0; i < poses.size(); ++i) cameras[i].camera_to_world = poses[i];
  // The official solves with the cameras' +z axes (pointing backwards); the lines are the same.
  const auto center = closest_point_to_axes(cameras);
  if (!center) throw Error(where + ": spherify: the cameras' optical axes are parallel; a 360° capture looks inward");
  Vec3 up{0, 0, 0};
  for (const auto& p : poses) up = add(up, sub(column(p, 3), *center));
  const Vec3 v0 = normalize(up);
  const Vec3 v1 = normalize(cross({0.1, 0.2, 0.3}, v0));
  const Vec3 v2 = normalize(cross(v0, v1));
  const Matrix34 frame = from_columns(v1, v2, v0, *center);
  double mean_square = 0;
  for (auto& p : poses) {
    p = inverse_times(frame, p);
    mean_square += dot(column(p, 3), column(p, 3)) / static_cast<double>(poses.size());
  }
  const double s = 1.0 / std::sqrt(mean_square);
  for (auto& p : poses) {
    for (int r = 0; r < 3; ++r) p[4 * r + 3] *= s;
  }
  for (auto& b : bounds) b = {b[0] * s, b[1] * s};
}

// The official loader's list: the folder's images sorted by name.
std::vector<std::string> list_images(const std::string& folder) {
  std::vector<std::string> files;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    if (entry.is_regular_file() && has_image_extension(entry.path())) files.push_back(entry.path().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

// poses_bounds.npy: [N][17] = a 3×5 matrix per view (rotation columns down, right, backwards; position; h, w,
// focal), then its near and far depth bounds.
void read_poses_bounds(const std::string& file, LlffCapture& capture) {
  const io::NpyArray array = io::read_npy(file);
  if (array.shape.size() != 2 || array.shape[1] != 17 || array.shape[0] == 0) {
    std::string shape;
    for (size_t d : array.shape) shape += (shape.empty() ? "" : "x") + std::to_string(d);
    throw Error(file + ": shape " + (shape.empty() ? "()" : shape) +
                "; expected N x 17 (a 3x5 pose and 2 bounds a view)");
  }
  for (size_t i = 0; i < array.shape[0]; ++i) {
    const double* row = array.values.data() + 17 * i;
    const std::string where = file + ": view " + std::to_string(i);
    for (int k = 0; k < 17; ++k) {
      if (!std::isfinite(row[k])) throw Error(where + ": value " + std::to_string(k) + " is not finite");
    }
    if (!(row[15] > 0) || !(row[16] > row[15])) {
      throw Error(where + ": bounds near " + std::to_string(row[15]) + ", far " + std::to_string(row[16]) +
                  ": need 0 < near < far");
    }
    if (!(row[4] >= 1) || !(row[9] >= 1) || !(row[14] > 0)) {
      throw Error(where + ": h, w, focal = " + std::to_string(row[4]) + ", " + std::to_string(row[9]) + ", " +
                  std::to_string(row[14]) + ": need a positive size and focal length");
    }
    // Columns: down, right, backwards → OpenGL's right (= old column 1), up (= −old column 0), backwards.
    auto at = [row](int r, int c) { return row[5 * r + c]; };
    Matrix34 pose;
    for (int r = 0; r < 3; ++r) {
      pose[4 * r + 0] = at(r, 1);
      pose[4 * r + 1] = -at(r, 0);
      pose[4 * r + 2] = at(r, 2);
      pose[4 * r + 3] = at(r, 3);
    }
    check_rigid_pose(pose, where);
    capture.camera_to_world.push_back(pose);
    capture.bounds.push_back({row[15], row[16]});
    if (i == 0) {
      capture.height_px = static_cast<uint32_t>(std::lround(row[4]));
      capture.width_px = static_cast<uint32_t>(std::lround(row[9]));
      capture.focal_px = row[14];
    }
  }
}

// After the bd_factor rescale the nearest bound is 4/3 scene units. A camera or a far bound beyond kMaxSceneUnits of
// them cannot be one capture (float32 rays keep no precision there, and the render path's products overflow double:
// a fuzzed file with positions of 1e222 made NaN cameras), so the file is refused before anything uses it.
constexpr double kMaxSceneUnits = 1e6;

void check_scene_extent(const LlffCapture& capture, const std::string& file) {
  for (size_t i = 0; i < capture.camera_to_world.size(); ++i) {
    const Vec3 position = column(capture.camera_to_world[i], 3);
    const double distance = std::sqrt(dot(position, position));
    const double far_bound = capture.bounds[i][1];
    if (!(distance <= kMaxSceneUnits) || !(far_bound <= kMaxSceneUnits)) {
      throw Error(file + ": view " + std::to_string(i) + ": position " + std::to_string(distance) + " and far bound " +
                  std::to_string(far_bound) + " scene units from the origin, with the nearest bound scaled to 4/3: " +
                  "more than 1e6 of them, so the poses and bounds are not of one capture");
    }
  }
}

}  // namespace

bool is_llff_folder(const std::string& dir) {
  std::error_code ec;
  return fs::is_regular_file(fs::path(dir) / "poses_bounds.npy", ec);
}

LlffCapture read_llff(const std::string& dir, const LoadOptions& options) {
  LlffCapture capture;
  capture.dir = dir;
  const std::string file = (fs::path(dir) / "poses_bounds.npy").string();
  read_poses_bounds(file, capture);

  // The official loader reads images_<factor>/ with focal / factor; without that folder we downsample images/.
  const fs::path at_factor = fs::path(dir) / ("images_" + std::to_string(options.factor));
  std::error_code ec;
  if (options.factor > 1 && fs::is_directory(at_factor, ec)) {
    capture.image_dir = at_factor.string();
    capture.stored_factor = options.factor;
    capture.focal_px /= options.factor;
  } else {
    capture.image_dir = (fs::path(dir) / "images").string();
  }
  if (!fs::is_directory(capture.image_dir, ec)) {
    // What the capture does hold (e.g. only images_8/, as the downsampled LLFF releases): say which factor reads it.
    std::string present;
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
      const std::string name = entry.path().filename().string();
      if (entry.is_directory(ec) && name.rfind("images_", 0) == 0) present += (present.empty() ? "" : ", ") + name;
    }
    throw Error(dir + ": an LLFF capture without its images at factor " + std::to_string(options.factor) +
                ": expected " + capture.image_dir + "/" +
                (present.empty() ? std::string()
                                 : " (it holds " + present + "/: give --set factor=N to train on images_N/)"));
  }
  capture.image_files = list_images(capture.image_dir);
  if (capture.image_files.size() != capture.camera_to_world.size()) {
    throw Error(capture.image_dir + ": " + std::to_string(capture.image_files.size()) + " images, but " + file +
                " has " + std::to_string(capture.camera_to_world.size()) + " poses");
  }

  // bd_factor 0.75: the nearest bound becomes 1/0.75, so NDC's near plane at depth 1 lies in front of the scene.
  double nearest = capture.bounds[0][0];
  for (const auto& b : capture.bounds) nearest = std::min(nearest, b[0]);
  const double s = 1.0 / (nearest * 0.75);
  scale_positions(capture.camera_to_world, s);
  for (auto& b : capture.bounds) b = {b[0] * s, b[1] * s};
  check_scene_extent(capture, file);

  recentre(capture.camera_to_world);
  capture.spherify = options.llff.spherify;
  if (capture.spherify) spherify(capture.camera_to_world, capture.bounds, file);
  return capture;
}

bool looks_360(const LlffCapture& capture) { return !looks_forward(capture.camera_to_world); }

namespace detail {

std::vector<SplitSpec> parse_llff(const std::string& dir, const LoadOptions& options) {
  if (options.holdout_every < 0) throw Error("holdout_every must be >= 0");
  const LlffCapture capture = read_llff(dir, options);
  const std::string source = (fs::path(dir) / "poses_bounds.npy").string();
  double near = 0.0, far = 1.0;  // NDC: the near plane to infinity
  if (capture.spherify || !options.llff.ndc) {
    // World rays between the scene's bounds (the original NeRF's choice for LLFF without NDC).
    near = capture.bounds[0][0];
    far = capture.bounds[0][1];
    for (const auto& b : capture.bounds) {
      near = std::min(near, b[0]);
      far = std::max(far, b[1]);
    }
    near *= 0.9;
  }
  near = options.near.value_or(near);
  far = options.far.value_or(far);
  if (!(near >= 0.0) || !(far > near)) {
    throw Error(source + ": near = " + std::to_string(near) + ", far = " + std::to_string(far) +
                ": need 0 <= near < far");
  }
  SplitSpec train{"train", source, true, {}}, test{"test", source, true, {}};
  for (size_t i = 0; i < capture.image_files.size(); ++i) {
    FrameSpec frame;
    frame.image_path = capture.image_files[i];
    frame.where = source + ": view " + std::to_string(i) + " (" + fs::path(frame.image_path).filename().string() + ")";
    frame.camera_to_world = capture.camera_to_world[i];
    frame.intrinsics.focal_x_px = capture.focal_px;
    frame.intrinsics.focal_y_px = capture.focal_px;
    frame.near = near;
    frame.far = far;
    frame.stored_factor = capture.stored_factor;
    const bool held_out = options.holdout_every > 0 && i % static_cast<size_t>(options.holdout_every) == 0;
    (held_out ? test : train).frames.push_back(frame);
  }
  // The official evaluates on the held-out views; they are also the val split `train` scores at its end.
  return with_held_out_splits(std::move(train), std::move(test), options);
}

}  // namespace detail

std::vector<Matrix34> spiral_poses(const std::vector<Matrix34>& camera_to_world, double nearest_depth,
                                   double farthest_depth, int frames) {
  // The official _generate_spiral_poses.
  std::vector<Matrix34> path;
  const Matrix34 average = average_pose(camera_to_world);
  Vec3 up{0, 0, 0};
  for (const auto& pose : camera_to_world) up = add(up, column(pose, 1));
  up = normalize(up);
  const double close = nearest_depth * 0.9;
  const double far_depth = farthest_depth * 5.0;
  const double dt = 0.75;
  const double focus = 1.0 / ((1.0 - dt) / close + dt / far_depth);
  // Radii: the 90th percentile of |position| per axis.
  Vec3 radii{};
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> values;
    for (const auto& p : camera_to_world) values.push_back(std::abs(p[4 * axis + 3]));
    std::sort(values.begin(), values.end());
    const double rank = 0.9 * static_cast<double>(values.size() - 1);  // numpy's linear percentile
    const size_t lo = static_cast<size_t>(std::floor(rank));
    const size_t hi = std::min(lo + 1, values.size() - 1);
    radii[axis] = values[lo] + (rank - static_cast<double>(lo)) * (values[hi] - values[lo]);
  }
  const double turns = 2.0, z_rate = 0.5;
  auto transform = [&average](Vec3 p) {
    return Vec3{dot({average[0], average[1], average[2]}, p) + average[3],
                dot({average[4], average[5], average[6]}, p) + average[7],
                dot({average[8], average[9], average[10]}, p) + average[11]};
  };
  for (int k = 0; k < frames; ++k) {
    const double theta = 2.0 * M_PI * turns * k / frames;
    const Vec3 c =
        transform({std::cos(theta) * radii[0], -std::sin(theta) * radii[1], -std::sin(theta * z_rate) * radii[2]});
    const Vec3 z = normalize(sub(c, transform({0, 0, -focus})));
    path.push_back(view_matrix(z, up, c));
  }
  return path;
}

std::vector<Camera> llff_render_path(const LlffCapture& capture, const LoadOptions& options, int frames) {
  if (frames < 1) throw Error("the render path needs at least one frame");
  std::vector<Matrix34> path;
  if (!capture.spherify) {
    double close = capture.bounds[0][0], far_depth = capture.bounds[0][1];
    for (size_t i = 0; i < capture.camera_to_world.size(); ++i) {
      close = std::min(close, capture.bounds[i][0]);
      far_depth = std::max(far_depth, capture.bounds[i][1]);
    }
    path = spiral_poses(capture.camera_to_world, close, far_depth, frames);
  } else {
    // The official spherical path: a circle at the cameras' mean height, looking at the centre, at angles
    // np.linspace(0, 2π, frames), whose last angle is 2π: the last frame repeats the first, as the official's does.
    Vec3 centroid{0, 0, 0};
    double mean_square = 0;
    for (const auto& p : capture.camera_to_world) {
      centroid = add(centroid, scale(column(p, 3), 1.0 / static_cast<double>(capture.camera_to_world.size())));
      mean_square += dot(column(p, 3), column(p, 3)) / static_cast<double>(capture.camera_to_world.size());
    }
    const double height = centroid[2];
    const double radius = std::sqrt(std::max(mean_square - height * height, 0.0));
    for (int k = 0; k < frames; ++k) {
      const double theta = frames > 1 ? 2.0 * M_PI * k / (frames - 1) : 0.0;
      const Vec3 origin{radius * std::cos(theta), radius * std::sin(theta), height};
      const Vec3 z = normalize(origin);
      const Vec3 x = normalize(cross(z, {0, 0, -1}));
      path.push_back(from_columns(x, normalize(cross(z, x)), z, origin));
    }
  }
  // Cameras as the loader makes them: the stored images' size and focal length, its near/far.
  LoadOptions one = options;
  one.splits = {"train"};
  one.holdout_every = 0;
  const auto specs = detail::parse_llff(capture.dir, one);
  std::vector<Camera> cameras;
  const detail::FrameSpec& frame = specs.at(0).frames.at(0);
  const uint32_t factor = std::max<uint32_t>(1, options.factor / capture.stored_factor);
  for (const auto& pose : path) {
    // Degenerate captures (every camera at one point, up vectors that cancel) leave a zero vector to normalise.
    for (double v : pose) {
      if (!std::isfinite(v)) {
        throw Error(capture.dir + ": no render path for this capture: its cameras' positions or up vectors are " +
                    "degenerate (a zero-length axis); render its views with --split instead");
      }
    }
    Camera camera;
    camera.camera_to_world = pose;
    camera.width_px = capture.width_px / capture.stored_factor / factor;
    camera.height_px = capture.height_px / capture.stored_factor / factor;
    camera.focal_x_px = camera.focal_y_px = capture.focal_px / factor;
    camera.center_x_px = camera.width_px / 2.0;
    camera.center_y_px = camera.height_px / 2.0;
    camera.near = frame.near;
    camera.far = frame.far;
    cameras.push_back(camera);
  }
  return cameras;
}

}  // namespace mipnerf::data
