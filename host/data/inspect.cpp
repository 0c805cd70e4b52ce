// Per-split summaries of a dataset.
#include "data/inspect.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "core/lens_models.hpp"
#include "data/lens_tables.hpp"

namespace mipnerf::data {
namespace {

template <typename T>
void widen(T& low, T& high, T value, bool first) {
  low = first ? value : std::min(low, value);
  high = first ? value : std::max(high, value);
}

std::string number(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.4g", v);
  return text;
}

// "OPENCV (k1 -0.12, k2 0.01, p1 0.001, p2 0), largest distortion 14.2 px" for each distinct lens of scale 0.
std::vector<std::string> lens_descriptions(const Split& split) {
  std::map<std::string, double> largest;  // description → largest distortion, px
  for (size_t c = 0; c < split.cameras.size(); ++c) {
    const Camera& cam = split.cameras[c];
    if (cam.lens.is_pinhole() || split.scale_levels[c] != 0) continue;
    const LensRow& row = lens_row(cam.lens.model);
    std::string text = std::string(row.colmap_name) + " (";
    for (size_t i = 0; i < row.coefficients.size(); ++i) {
      text += (i ? ", " : "") + std::string(row.coefficients[i].name) + " " + number(cam.lens.*row.coefficients[i].value);
    }
    text += ")";
    largest[text] = std::max(largest[text], largest_distortion_px(cam));
  }
  std::vector<std::string> out;
  for (const auto& [text, px] : largest) out.push_back(text + ", largest distortion " + number(px) + " px");
  return out;
}

}  // namespace

SplitSummary summarize(const Split& split) {
  SplitSummary s;
  s.name = split.name;
  s.source = split.source;
  s.images = split.num_images();
  s.pixels = split.num_pixels();
  std::map<uint32_t, ScaleSummary> scales;
  for (size_t c = 0; c < split.cameras.size(); ++c) {
    const Camera& cam = split.cameras[c];
    const bool first_camera = c == 0;
    auto [it, inserted] = scales.try_emplace(split.scale_levels[c]);
    ScaleSummary& level = it->second;
    level.level = split.scale_levels[c];
    ++level.images;
    widen(level.width_min, level.width_max, cam.width_px, inserted);
    widen(level.height_min, level.height_max, cam.height_px, inserted);
    widen(level.focal_x_min, level.focal_x_max, cam.focal_x_px, inserted);
    widen(level.focal_y_min, level.focal_y_max, cam.focal_y_px, inserted);
    widen(level.lossmult_min, level.lossmult_max, cam.lossmult, inserted);
    widen(s.near_min, s.near_max, cam.near, first_camera);
    widen(s.far_min, s.far_max, cam.far, first_camera);
    const Vec3 o = camera_center(cam);
    for (int k = 0; k < 3; ++k) widen(s.center_min[k], s.center_max[k], o[k], first_camera);
    widen(s.radius_min, s.radius_max, std::sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]), first_camera);
  }
  for (const auto& [level, summary] : scales) s.scales.push_back(summary);
  s.lenses = lens_descriptions(split);

  std::vector<Matrix34> poses;
  for (const auto& cam : split.cameras) poses.push_back(cam.camera_to_world);
  s.forward_facing = looks_forward(poses);
  Vec3 axes_sum{0, 0, 0};
  for (const auto& cam : split.cameras) axes_sum = add(axes_sum, optical_axis(cam));
  if (length(axes_sum) > 1e-9 * static_cast<double>(split.cameras.size())) {
    s.view_direction = normalize(axes_sum);
    for (const auto& cam : split.cameras) {
      const double cosine = std::clamp(dot(optical_axis(cam), s.view_direction), -1.0, 1.0);
      s.axis_spread_deg = std::max(s.axis_spread_deg, std::acos(cosine) * 180.0 / M_PI);
    }
  }
  s.look_at = closest_point_to_axes(split.cameras);
  if (s.look_at) {
    const Vec3& p = *s.look_at;
    for (size_t c = 0; c < split.cameras.size(); ++c) {
      const Vec3 o = camera_center(split.cameras[c]), d = optical_axis(split.cameras[c]);
      const Vec3 to_p{p[0] - o[0], p[1] - o[1], p[2] - o[2]};
      const double depth = to_p[0] * d[0] + to_p[1] * d[1] + to_p[2] * d[2];
      if (depth > 0) ++s.cameras_facing;
      const double squared = to_p[0] * to_p[0] + to_p[1] * to_p[1] + to_p[2] * to_p[2];
      s.axis_miss_max = std::max(s.axis_miss_max, std::sqrt(std::max(0.0, squared - depth * depth)));
      widen(s.look_at_depth_min, s.look_at_depth_max, depth, c == 0);
    }
  }
  double sum[3] = {0, 0, 0};
  for (size_t i = 0; i < split.rgb.size(); ++i) sum[i % 3] += split.rgb[i];
  for (int k = 0; k < 3; ++k) s.mean_rgb[k] = split.num_pixels() ? sum[k] / split.num_pixels() : 0.0;
  return s;
}

}  // namespace mipnerf::data
