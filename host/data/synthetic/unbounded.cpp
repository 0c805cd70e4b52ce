// The unbounded scene: ground, pillars, sky, the orbit of cameras, the LLFF writer.
#include "data/synthetic/unbounded.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "data/pose.hpp"
#include "data/synthetic/llff_writer.hpp"

namespace mipnerf::data {
namespace {

constexpr double kGroundZ = -0.7;           // just under the procedural scene's slab, as the forward-facing floor
constexpr uint32_t kStreamOrbit = 0x5CE2u;  // host-only Philox stream of the azimuth jitter

// A cheap hash of a lattice point and an octave to [0, 1): splitmix64's finaliser over a mix of the four.
double lattice_value(int64_t i, int64_t j, uint64_t layer, int64_t k = 0) {
  uint64_t h = static_cast<uint64_t>(i) * 0x9E3779B97F4A7C15ull ^ static_cast<uint64_t>(j) * 0xC2B2AE3D27D4EB4Full ^
               static_cast<uint64_t>(k) * 0xD6E8FEB86659FD93ull ^ (layer + 1) * 0x165667B19E3779F9ull;
  h ^= h >> 30;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 27;
  h *= 0x94D049BB133111EBull;
  h ^= h >> 31;
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}

// Value noise in [0, 1]: five octaves of smoothstep-interpolated lattice values, cells from `cell` down to cell/16,
// amplitudes halving. Not periodic, so that structure-from-motion can tell one patch from another (a checker's
// every corner looks like every other, and COLMAP matched them across the orbit into a wrong model).
double value_noise(double x, double y, double cell, uint64_t layer) {
  double sum = 0, weight = 0, amplitude = 1;
  for (int octave = 0; octave < 5; ++octave, cell *= 0.5, amplitude *= 0.5) {
    const double u = x / cell, v = y / cell;
    const double fu = std::floor(u), fv = std::floor(v);
    const auto i = static_cast<int64_t>(fu), j = static_cast<int64_t>(fv);
    const double su = (u - fu) * (u - fu) * (3 - 2 * (u - fu)), sv = (v - fv) * (v - fv) * (3 - 2 * (v - fv));
    const uint64_t key = layer * 8 + static_cast<uint64_t>(octave);
    const double bottom = lattice_value(i, j, key) + su * (lattice_value(i + 1, j, key) - lattice_value(i, j, key));
    const double top =
        lattice_value(i, j + 1, key) + su * (lattice_value(i + 1, j + 1, key) - lattice_value(i, j + 1, key));
    sum += amplitude * (bottom + sv * (top - bottom));
    weight += amplitude;
  }
  return sum / weight;
}

// Value noise in 3D, one octave, trilinear over smoothstep weights: the brightness of the central scene's surfaces.
double value_noise3(const std::array<double, 3>& p, double cell, uint64_t layer) {
  double s[3], fl[3];
  int64_t c[3];
  for (int a = 0; a < 3; ++a) {
    fl[a] = std::floor(p[a] / cell);
    c[a] = static_cast<int64_t>(fl[a]);
    const double f = p[a] / cell - fl[a];
    s[a] = f * f * (3 - 2 * f);
  }
  double sum = 0;
  for (int corner = 0; corner < 8; ++corner) {
    double w = 1;
    for (int a = 0; a < 3; ++a) w *= (corner >> a & 1) ? s[a] : 1 - s[a];
    sum += w * lattice_value(c[0] + (corner & 1), c[1] + (corner >> 1 & 1), layer, c[2] + (corner >> 2 & 1));
  }
  return sum;
}

// Blends two colours by a noise value stretched about its mean (value noise bunches around 0.5), clamped.
std::array<double, 3> noise_colour(const std::array<double, 3>& a, const std::array<double, 3>& b, double noise) {
  const double mix = std::clamp(0.5 + 2.5 * (noise - 0.5), 0.0, 1.0);
  return {a[0] + mix * (b[0] - a[0]), a[1] + mix * (b[1] - a[1]), a[2] + mix * (b[2] - a[2])};
}

// A vertical box standing on the ground: centre (x, y), half-widths, height; horizontal stripes of `period`.
struct Pillar {
  double x, y, half_x, half_y, height, period;
  std::array<double, 3> colors[2];
};
const Pillar kPillars[] = {
    {6.0, 1.5, 0.4, 0.4, 3.0, 0.3, {{0.75, 0.2, 0.15}, {0.9, 0.85, 0.7}}},
    {-4.5, 5.0, 0.6, 0.3, 4.0, 0.5, {{0.15, 0.3, 0.7}, {0.85, 0.85, 0.85}}},
    {-8.0, -3.0, 0.5, 0.5, 5.0, 0.4, {{0.2, 0.55, 0.25}, {0.9, 0.9, 0.6}}},
    {2.0, -9.0, 0.8, 0.8, 6.0, 0.8, {{0.55, 0.2, 0.55}, {0.95, 0.8, 0.9}}},
    {14.0, 10.0, 1.5, 1.0, 9.0, 1.2, {{0.7, 0.5, 0.1}, {0.2, 0.15, 0.1}}},
    {-16.0, 12.0, 1.2, 1.2, 12.0, 1.5, {{0.3, 0.3, 0.35}, {0.85, 0.85, 0.9}}},
    {-12.0, -20.0, 2.0, 1.5, 10.0, 2.0, {{0.6, 0.1, 0.1}, {0.95, 0.95, 0.95}}},
    {25.0, -30.0, 3.0, 3.0, 20.0, 3.0, {{0.1, 0.35, 0.4}, {0.8, 0.9, 0.9}}},
};

// Slab test of a ray against a pillar's box; on a hit the distance and the surface colour (shaded by its face):
// stripes, or with `noise` its two colours blended by value noise over the face (one noise layer per pillar).
bool hit_pillar(const Pillar& p, size_t index, bool noise, const Ray& ray, double& t_hit, std::array<double, 3>& rgb) {
  const auto& o = ray.origin_world;
  const auto& d = ray.direction_world;
  const double lo[3] = {p.x - p.half_x, p.y - p.half_y, kGroundZ}, hi[3] = {p.x + p.half_x, p.y + p.half_y,
                                                                           kGroundZ + p.height};
  double t_near = 1e-9, t_far = std::numeric_limits<double>::infinity();
  int axis_near = -1;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) {
      if (o[a] < lo[a] || o[a] > hi[a]) return false;
      continue;
    }
    double t0 = (lo[a] - o[a]) / d[a], t1 = (hi[a] - o[a]) / d[a];
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > t_near) {
      t_near = t0;
      axis_near = a;
    }
    t_far = std::min(t_far, t1);
    if (t_near > t_far) return false;
  }
  if (axis_near < 0) return false;  // the ray starts inside: not a view from outside
  t_hit = t_near;
  const double z = o[2] + t_near * d[2];
  std::array<double, 3> albedo = p.colors[static_cast<int>(std::floor((z - kGroundZ) / p.period)) & 1];
  if (noise) {
    // Across the face: x on the faces facing ±y, y on those facing ±x, x + y on the top.
    const double along = axis_near == 1 ? o[0] + t_near * d[0] : axis_near == 0 ? o[1] + t_near * d[1]
                                                                                : o[0] + o[1] + t_near * (d[0] + d[1]);
    albedo = noise_colour(p.colors[0], p.colors[1], value_noise(along, z, p.period, 16 + index));
  }
  const double light = axis_near == 2 ? 1.0 : axis_near == 0 ? 0.8 : 0.65;
  for (int c = 0; c < 3; ++c) rgb[c] = albedo[c] * light;
  return true;
}

// The sky: a horizon-to-zenith gradient with soft bands in azimuth, so that the background has detail to learn.
std::array<double, 3> sky(const std::array<double, 3>& d) {
  const double norm = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  const double up = std::max(0.0, d[2] / norm);
  const double band = 0.5 + 0.5 * std::cos(6.0 * std::atan2(d[1], d[0]));
  return {0.55 + 0.25 * (1 - up) + 0.1 * band * (1 - up), 0.65 + 0.2 * (1 - up), 0.9 - 0.05 * band * (1 - up)};
}

// 0.9× the nearest and 1.1× the 99th percentile of the finite depths the camera sees.
std::array<double, 2> finite_depth_bounds(const Camera& camera) {
  const std::vector<double> depths = traced_depths(camera, trace_unbounded);
  if (depths.empty()) throw Error("unbounded scene: a camera sees only sky (a camera placement bug)");
  const size_t high = std::min(depths.size() - 1, static_cast<size_t>(0.99 * (depths.size() - 1) + 0.5));
  return {0.9 * depths.front(), 1.1 * depths[high]};
}

}  // namespace

namespace {

SceneHit trace_outdoors(const Ray& ray, UnboundedTexture texture) {
  const bool noise = texture == UnboundedTexture::noise;
  SceneHit hit = trace_procedural(ray);
  const auto& o = ray.origin_world;
  const auto& d = ray.direction_world;
  if (hit.hit) {
    if (noise) {
      // The central scene's checkers and stripes look alike from every side: COLMAP matched the sphere's squares
      // across the orbit and put every camera on one side. A brightness of two noise scales tells them apart.
      const std::array<double, 3> at{o[0] + hit.t * d[0], o[1] + hit.t * d[1], o[2] + hit.t * d[2]};
      const double n = 0.6 * value_noise3(at, 0.25, 40) + 0.4 * value_noise3(at, 0.08, 41);
      const double brightness = std::clamp(0.3 + 1.4 * n, 0.2, 1.2);
      for (double& c : hit.rgb) c = std::min(1.0, c * brightness);
    }
    return hit;
  }
  double best = std::numeric_limits<double>::infinity();
  if (d[2] < 0) {
    const double t = (kGroundZ - o[2]) / d[2];
    if (t > 1e-9) {
      best = t;
      const double x = o[0] + t * d[0], y = o[1] + t * d[1];
      const std::array<double, 3> dark{0.32, 0.3, 0.26}, light{0.6, 0.56, 0.48};
      if (noise) {
        hit.rgb = noise_colour(dark, light, value_noise(x, y, 1.0, 0));
      } else {
        const bool odd = ((static_cast<int>(std::floor(x)) ^ static_cast<int>(std::floor(y))) & 1) != 0;
        hit.rgb = odd ? dark : light;
      }
    }
  }
  for (size_t p = 0; p < std::size(kPillars); ++p) {
    double t = 0;
    std::array<double, 3> rgb{};
    if (hit_pillar(kPillars[p], p, noise, ray, t, rgb) && t < best) {
      best = t;
      hit.rgb = rgb;
    }
  }
  hit.hit = true;
  hit.t = best;
  if (!std::isfinite(best)) hit.rgb = sky(d);
  return hit;
}

}  // namespace

SceneHit trace_unbounded(const Ray& ray) { return trace_outdoors(ray, UnboundedTexture::checker); }
SceneHit trace_unbounded_noise(const Ray& ray) { return trace_outdoors(ray, UnboundedTexture::noise); }

SceneHit (*unbounded_tracer(UnboundedTexture texture))(const Ray&) {
  return texture == UnboundedTexture::noise ? trace_unbounded_noise : trace_unbounded;
}

void validate(const UnboundedOptions& o) {
  const uint32_t divisor = 4 * std::max<uint32_t>(o.factor, 1);
  if (o.width_px < 8 || o.width_px > 4096 || o.width_px % divisor != 0) {
    throw Error("make-scene --unbounded: --size must be 8 to 4096 and divisible by " + std::to_string(divisor) +
                " (4:3 images, downsampled by " + std::to_string(o.factor) + "), got " + std::to_string(o.width_px));
  }
  if (o.factor < 1 || o.factor > 16 || (o.factor & (o.factor - 1)) != 0) {
    throw Error("make-scene --unbounded: --factor must be a power of two from 1 to 16");
  }
  if (o.views < 8 || o.views > 400) throw Error("make-scene --unbounded: --views must be 8 to 400 (a full orbit)");
  if (o.samples_per_axis < 1 || o.samples_per_axis > 64) throw Error("make-scene: --samples must be 1 to 64");
}

std::vector<Camera> unbounded_cameras(const UnboundedOptions& options) {
  validate(options);
  std::vector<Camera> cameras;
  const uint32_t height = options.width_px * 3 / 4;
  for (uint32_t k = 0; k < options.views; ++k) {
    // Two interleaved rings: even views low (0.6), odd views high (1.6), each azimuth jittered by up to a third of
    // the spacing (deterministic in the seed), all looking at the scene's centre.
    const auto u = rng_uniform4(options.seed, k, 0, 0, kStreamOrbit);
    const double spacing = 2 * M_PI / options.views;
    const double azimuth = spacing * (k + (u[0] - 0.5) / 1.5);
    const double z = k % 2 == 0 ? 0.6 : 1.6;
    const Vec3 eye{options.camera_distance * std::cos(azimuth), options.camera_distance * std::sin(azimuth), z};
    Camera camera =
        centred_pinhole(look_at_pose(eye, {0.0, 0.0, 0.0}, {0, 0, 1}), options.width_px, height, options.camera_angle_x);
    const auto bounds = finite_depth_bounds(camera);
    camera.near = bounds[0];
    camera.far = bounds[1];
    cameras.push_back(camera);
  }
  return cameras;
}

void write_unbounded_scene(const std::string& out_dir, const UnboundedOptions& options, const LogFn& log) {
  const auto cameras = unbounded_cameras(options);
  write_llff_views(out_dir, cameras, unbounded_tracer(options.texture), llff_write_options(options, 0x55420000u));
  if (log) {
    log(LogLevel::info, "unbounded scene: " + std::to_string(cameras.size()) + " views around it at " +
                            std::to_string(options.width_px) + "x" + std::to_string(cameras[0].height_px) +
                            (options.factor > 1 ? " (and images_" + std::to_string(options.factor) + "/)" : ""));
  }
}

}  // namespace mipnerf::data
