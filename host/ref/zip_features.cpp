// Zip-NeRF's interval features in double precision (zip_features.hpp): multisamples, then the grid encoding's
// reference on them, then the mean over each interval's multisamples.
#include "ref/zip_features.hpp"

#include <algorithm>
#include <cmath>

#include "core/rng.hpp"
#include "ref/grid_encoding.hpp"
#include "ref/multisample.hpp"

namespace mipnerf::ref {
namespace {

constexpr uint32_t kMultisampleStream = rng_stream_multisample;  // RNG_STREAM_MULTISAMPLE

// The pattern of one interval, as multisample_pattern draws it (the float uniforms the kernel gets, bit for bit).
void interval_pattern(const ZipFeatureSettings& s, uint32_t ray_number, uint32_t interval, bool& reversed,
                      double& turn) {
  if (s.randomized) {
    const auto u = rng_uniform4(s.seed, ray_number, s.step, interval, kMultisampleStream);
    reversed = u[0] < 0.5f;
    turn = 2 * M_PI * u[1];
  } else {
    reversed = interval % 2 != 0;
    turn = reversed ? M_PI / 6 : 0.0;
  }
}

size_t level_count(const std::vector<uint32_t>& levels) { return levels.size() / 4; }

// The one point of [t0, t1] without multisampling: the frustum's mean on the axis, t_μ = s + 2sd²/(3s² + d²)
// (mip-NeRF eq. 7).
double frustum_mean_t(double t0, double t1) {
  const double s = 0.5 * (t0 + t1), d = 0.5 * (t1 - t0);
  const double denominator = 3 * s * s + d * d;
  return denominator < 1.1754943508222875e-38 ? t0 : s + 2 * s * d * d / denominator;
}

// A world point and its footprint into the grid's unit cube (the kernel's zip_to_unit_cube), contracted first when
// the settings say so.
void to_unit_cube(const ZipFeatureSettings& s, const double point_world[3], double scale_world, double* unit_point,
                  double& scale) {
  double point[3] = {point_world[0], point_world[1], point_world[2]};
  if (s.contract) {
    zip_contract(point_world, point);
    scale_world *= zip_contract_isoscale(point_world);
  }
  for (int a = 0; a < 3; ++a) unit_point[a] = (point[a] - s.box[a]) / s.box[3];
  scale = scale_world / s.box[3];
}

}  // namespace

void zip_contract(const double x[3], double out[3]) {
  const double m = std::max(1.0, x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
  const double scale = (2 * std::sqrt(m) - 1) / m;
  for (int a = 0; a < 3; ++a) out[a] = scale * x[a];
}

double zip_contract_isoscale(const double x[3]) {
  const double m = std::max(1.0, x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
  return std::exp(2.0 / 3.0 * std::log(2 * std::sqrt(m) - 1) - std::log(m));
}

void zip_multisamples(const ZipRays& rays, const ZipFeatureSettings& s, std::vector<double>& unit_points,
                      std::vector<double>& scales) {
  const size_t n_samples = rays.n_rays * rays.n_intervals, per_interval = zip_points_per_interval(s);
  unit_points.assign(n_samples * per_interval * 3, 0.0);
  scales.assign(n_samples * per_interval, 0.0);
  for (size_t ray = 0; ray < rays.n_rays; ++ray) {
    const Vec3d origin{rays.origins[3 * ray], rays.origins[3 * ray + 1], rays.origins[3 * ray + 2]};
    const Vec3d direction{rays.directions[3 * ray], rays.directions[3 * ray + 1], rays.directions[3 * ray + 2]};
    for (size_t i = 0; i < rays.n_intervals; ++i) {
      const double* edges = &rays.t_edges[ray * (rays.n_intervals + 1) + i];
      const size_t first = (ray * rays.n_intervals + i) * per_interval;
      if (!s.multisample) {
        // The hexagon's footprint at t_μ: √½·radius·t_μ (cone) or √½·radius (cylinder).
        const double t = frustum_mean_t(edges[0], edges[1]);
        const double point[3] = {origin[0] + direction[0] * t, origin[1] + direction[1] * t,
                                 origin[2] + direction[2] * t};
        to_unit_cube(s, point, s.scale_mult * std::sqrt(0.5) * rays.radii[ray] * (s.cylinder ? 1.0 : t),
                     &unit_points[3 * first], scales[first]);
        continue;
      }
      bool reversed = false;
      double turn = 0.0;
      interval_pattern(s, s.first_ray + static_cast<uint32_t>(ray), static_cast<uint32_t>(i), reversed, turn);
      const Multisamples m =
          hexify_multisamples(origin, direction, rays.radii[ray], edges[0], edges[1], reversed, turn, s.cylinder);
      for (size_t j = 0; j < per_interval; ++j) {
        const size_t p = first + j;
        const double point[3] = {m.points_world[j][0], m.points_world[j][1], m.points_world[j][2]};
        to_unit_cube(s, point, s.scale_mult * m.perp_radius[j], &unit_points[3 * p], scales[p]);
      }
    }
  }
}

std::vector<double> zip_level_scale(const std::vector<uint32_t>& levels, const std::vector<double>& table,
                                    int features, double maxval) {
  std::vector<double> out;
  for (size_t l = 0; l < level_count(levels); ++l) {
    const size_t first = size_t(levels[4 * l]) * features, count = size_t(levels[4 * l + 2]) * features;
    double sum = 0.0;
    for (size_t i = 0; i < count; ++i) sum += table[first + i] * table[first + i];
    out.push_back(std::sqrt(maxval * maxval + sum / double(count)));
  }
  return out;
}

void zip_features_fwd(const ZipRays& rays, const std::vector<uint32_t>& levels, const std::vector<double>& table,
                      const std::vector<double>& level_scale, const ZipFeatureSettings& s,
                      std::vector<double>& features) {
  std::vector<double> points, scales, point_features;
  zip_multisamples(rays, s, points, scales);
  grid_encoding_fwd(levels, points, scales, table, s.features, s.downweight, point_features);
  const size_t n_levels = level_count(levels), width = s.features + (s.append_scale ? 1 : 0);
  const size_t n_samples = rays.n_rays * rays.n_intervals;
  const size_t per_interval = zip_points_per_interval(s);
  const double mean = s.precondition / per_interval;
  features.assign(n_samples * n_levels * width, 0.0);
  for (size_t sample = 0; sample < n_samples; ++sample) {
    for (size_t l = 0; l < n_levels; ++l) {
      double* out = &features[(sample * n_levels + l) * width];
      for (size_t j = 0; j < per_interval; ++j) {
        const size_t p = sample * per_interval + j;
        for (int f = 0; f < s.features; ++f) out[f] += mean * point_features[(p * n_levels + l) * s.features + f];
        if (s.append_scale) {
          const double weight = s.downweight ? level_feature_weight(scales[p] * levels[4 * l + 1]) : 1.0;
          out[s.features] += mean * (2 * weight - 1) * level_scale[l];
        }
      }
    }
  }
}

void zip_features_bwd(const ZipRays& rays, const std::vector<uint32_t>& levels, const std::vector<double>& d_features,
                      const ZipFeatureSettings& s, std::vector<double>& d_table) {
  std::vector<double> points, scales;
  zip_multisamples(rays, s, points, scales);
  const size_t n_levels = level_count(levels), width = s.features + (s.append_scale ? 1 : 0);
  const size_t n_samples = rays.n_rays * rays.n_intervals;
  const size_t per_interval = zip_points_per_interval(s);
  const double mean = s.precondition / per_interval;
  // Every point of an interval gets the interval's gradient / P (the mean's), then the grid's backward.
  std::vector<double> d_points(n_samples * per_interval * n_levels * s.features);
  for (size_t sample = 0; sample < n_samples; ++sample) {
    for (size_t j = 0; j < per_interval; ++j) {
      for (size_t l = 0; l < n_levels; ++l) {
        for (int f = 0; f < s.features; ++f) {
          d_points[((sample * per_interval + j) * n_levels + l) * s.features + f] =
              mean * d_features[(sample * n_levels + l) * width + f];
        }
      }
    }
  }
  grid_encoding_bwd(levels, points, scales, d_points, s.features, s.downweight, d_table);
}

void grid_weight_decay(const std::vector<uint32_t>& levels, const std::vector<double>& table, int features,
                       double mult, std::vector<double>& d_table) {
  for (size_t l = 0; l < level_count(levels); ++l) {
    const size_t first = size_t(levels[4 * l]) * features, count = size_t(levels[4 * l + 2]) * features;
    for (size_t i = first; i < first + count; ++i) d_table[i] += mult * table[i] / double(count);
  }
}

}  // namespace mipnerf::ref
