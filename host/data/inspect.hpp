// What a loaded dataset holds, summarised per split so that a convention mistake shows at once (cameras
// that look away from the scene, a look-at point far from the origin, wrong focal lengths or near/far).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "data/dataset.hpp"
#include "data/pose.hpp"

namespace mipnerf::data {

struct ScaleSummary {
  uint32_t level = 0;  // images downsampled by 2^level
  size_t images = 0;
  uint32_t width_min = 0, width_max = 0, height_min = 0, height_max = 0;
  double focal_x_min = 0, focal_x_max = 0, focal_y_min = 0, focal_y_max = 0;  // pixels
  double lossmult_min = 0, lossmult_max = 0;
};

struct SplitSummary {
  std::string name, source;
  size_t images = 0;
  uint64_t pixels = 0;
  std::vector<ScaleSummary> scales;  // by level
  double near_min = 0, near_max = 0, far_min = 0, far_max = 0;
  Vec3 center_min{}, center_max{};   // bounds of the camera centres (world)
  double radius_min = 0, radius_max = 0;  // camera distance from the origin
  bool forward_facing = false;       // every optical axis within 45° of their mean (data::looks_forward)
  // Where the cameras look: the mean of the optical axes (unit; zero when they cancel) and the largest angle between
  // an axis and it, in degrees. A forward-facing capture's nearly parallel axes need not meet, so this, not the
  // look-at centre, says where such a capture looks.
  Vec3 view_direction{};
  double axis_spread_deg = 0;
  std::optional<Vec3> look_at;       // least-squares point closest to all optical axes
  size_t cameras_facing = 0;         // cameras for which the look-at point lies in front (axis angle < 90°)
  double axis_miss_max = 0;          // largest distance from the look-at point to an optical axis
  double look_at_depth_min = 0, look_at_depth_max = 0;  // depth of the look-at point along each axis
  std::array<double, 3> mean_rgb{};  // mean composited colour
  // Each distinct lens of the split's full-resolution cameras: its model and coefficients, and the largest
  // displacement it makes over the image, in pixels (data/lens_tables.hpp). Empty when every camera is a pinhole.
  std::vector<std::string> lenses;
};

SplitSummary summarize(const Split& split);

}  // namespace mipnerf::data
