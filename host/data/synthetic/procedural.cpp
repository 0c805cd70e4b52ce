// The procedural scene: geometry, shading, cameras, the supersampled renderer and the writer.
#include "data/synthetic/procedural.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <mutex>
#include <thread>

#include "core/error.hpp"
#include "core/vec3.hpp"
#include "data/intrinsics.hpp"
#include "data/lens_tables.hpp"
#include "data/multiscale.hpp"
#include "data/pose.hpp"
#include "io/file.hpp"
#include "io/json.hpp"
#include "io/png.hpp"
#include "core/rng.hpp"

namespace mipnerf::data {
namespace {

// Host-only Philox streams of the generator (numbers never shared with the RNG_STREAM_* of the kernels,
// which are small integers).
constexpr uint32_t kStreamCameras = 0x5CE0u;
constexpr uint32_t kStreamJitter = 0x5CE1u;


// Two-colour patterns: index 0 or 1 of a periodic function of position.
int parity(double value) { return static_cast<int>(std::floor(value)) & 1; }

struct Sphere {
  Vec3 center;
  double radius;
  Vec3 colors[2];
  int sectors, bands;  // checker cells in longitude and latitude
};

// A box rotated about the world z axis, with stripes (or checkers) in its local frame.
struct Box {
  Vec3 center;
  Vec3 half_extent;
  double yaw;          // radians about z
  Vec3 colors[2];
  Vec3 stripe_normal;    // local direction along which the pattern alternates
  double period;       // of one stripe
  bool checker;        // checkers on the local x/y/z grid instead of stripes
};

const Sphere kSphere{{0.0, 0.0, 0.25}, 0.55, {{0.85, 0.12, 0.08}, {0.95, 0.95, 0.92}}, 24, 12};
const Box kBoxes[] = {
    // Fine horizontal stripes (period 0.06: ~1 pixel at 64×64, far below one at ×8).
    {{0.8, -0.55, -0.2}, {0.28, 0.28, 0.35}, 0.45, {{0.05, 0.1, 0.55}, {0.98, 0.85, 0.1}}, {0, 0, 1}, 0.06, false},
    // Diagonal black/white stripes.
    {{-0.75, 0.6, -0.25}, {0.35, 0.2, 0.3}, -0.6, {{0.03, 0.03, 0.03}, {0.97, 0.97, 0.97}}, {0.7071, 0.7071, 0}, 0.09,
     false},
    // A thin checkered slab under everything.
    {{0.0, 0.0, -0.6}, {1.0, 1.0, 0.04}, 0.2, {{0.15, 0.55, 0.2}, {0.8, 0.8, 0.75}}, {0, 0, 0}, 0.125, true},
};
const Vec3 kLightDir = normalize({0.45, 0.3, 0.85});
constexpr double kAmbient = 0.35, kDiffuse = 0.65;

Vec3 shade(Vec3 albedo, Vec3 normal) {
  const double light = kAmbient + kDiffuse * std::max(0.0, dot(normal, kLightDir));
  return {albedo[0] * light, albedo[1] * light, albedo[2] * light};
}

bool hit_sphere(const Ray& ray, double& t_hit, Vec3& rgb) {
  const Vec3 o = sub(ray.origin_world, kSphere.center);
  const Vec3& d = ray.direction_world;
  const double a = dot(d, d), half_b = dot(o, d), c = dot(o, o) - kSphere.radius * kSphere.radius;
  const double disc = half_b * half_b - a * c;
  if (disc < 0) return false;
  const double root = std::sqrt(disc);
  double t = (-half_b - root) / a;
  if (t <= 1e-9) t = (-half_b + root) / a;
  if (t <= 1e-9 || t >= t_hit) return false;
  const Vec3 n = normalize(add(o, scale(d, t)));
  const double longitude = std::atan2(n[1], n[0]) / (2.0 * M_PI) + 0.5;      // 0..1
  const double latitude = std::acos(std::clamp(n[2], -1.0, 1.0)) / M_PI;  // 0..1
  const int cell = parity(longitude * kSphere.sectors) ^ parity(latitude * kSphere.bands);
  t_hit = t;
  rgb = shade(kSphere.colors[cell], n);
  return true;
}

bool hit_box(const Box& box, const Ray& ray, double& t_hit, Vec3& rgb) {
  const double c = std::cos(box.yaw), s = std::sin(box.yaw);
  auto to_local = [c, s](Vec3 v) { return Vec3{c * v[0] + s * v[1], -s * v[0] + c * v[1], v[2]}; };
  const Vec3 o = to_local(sub(ray.origin_world, box.center));
  const Vec3 d = to_local(ray.direction_world);
  double t_enter = -1e300, t_exit = 1e300;
  int enter_axis = 0;
  double enter_sign = 1.0;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-300) {
      if (std::abs(o[k]) > box.half_extent[k]) return false;
      continue;
    }
    double t0 = (-box.half_extent[k] - o[k]) / d[k], t1 = (box.half_extent[k] - o[k]) / d[k];
    double sign = -1.0;  // entering through the −k face when t0 < t1
    if (t0 > t1) {
      std::swap(t0, t1);
      sign = 1.0;
    }
    if (t0 > t_enter) {
      t_enter = t0;
      enter_axis = k;
      enter_sign = sign;
    }
    t_exit = std::min(t_exit, t1);
  }
  if (t_enter > t_exit || t_enter <= 1e-9 || t_enter >= t_hit) return false;  // cameras are outside every box
  const Vec3 p = add(o, scale(d, t_enter));
  int cell;
  if (box.checker) {
    cell = parity(p[0] / box.period) ^ parity(p[1] / box.period) ^ parity(p[2] / box.period);
  } else {
    cell = parity(dot(p, box.stripe_normal) / box.period);
  }
  Vec3 n_local{0, 0, 0};
  n_local[enter_axis] = enter_sign;
  const Vec3 n{c * n_local[0] - s * n_local[1], s * n_local[0] + c * n_local[1], n_local[2]};
  t_hit = t_enter;
  rgb = shade(box.colors[cell], n);
  return true;
}

Camera camera_at(const Vec3& eye, const SceneOptions& options) {
  Camera camera = centred_pinhole(look_at_pose(eye, {0, 0, 0}, {0, 0, 1}), options.size_px, options.size_px,
                                  options.camera_angle_x);
  camera.near = options.near;
  camera.far = options.far;
  camera.lens = options.lens;
  return camera;
}

Vec3 on_sphere(double radius, double elevation, double azimuth) {
  return {radius * std::cos(elevation) * std::cos(azimuth), radius * std::cos(elevation) * std::sin(azimuth),
          radius * std::sin(elevation)};
}

uint32_t split_index(const std::string& split) {
  if (split == "train") return 0;
  if (split == "val") return 1;
  if (split == "test") return 2;
  throw Error("procedural scene: unknown split '" + split + "' (train, val or test)");
}

// Runs body(i) for i in [0, n) on `threads` threads; rethrows the first exception.
template <typename Body>
void parallel_for(size_t n, unsigned threads, Body body) {
  std::atomic<size_t> next{0};
  std::exception_ptr failure;
  std::mutex failure_mutex;
  auto worker = [&] {
    for (size_t i = next++; i < n; i = next++) {
      try {
        body(i);
      } catch (...) {
        std::lock_guard<std::mutex> lock(failure_mutex);
        if (!failure) failure = std::current_exception();
        next = n;
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned k = 1; k < threads && k < n; ++k) pool.emplace_back(worker);
  worker();
  for (auto& thread : pool) thread.join();
  if (failure) std::rethrow_exception(failure);
}

}  // namespace

void validate(const SceneOptions& o) {
  if (o.size_px < 2 || o.size_px > 4096) throw Error("make-scene: --size must be 2 to 4096, got " + std::to_string(o.size_px));
  if (o.train_views < 1) throw Error("make-scene: --views must be at least 1");
  if (o.train_views + o.val_views + o.test_views > 10000) throw Error("make-scene: at most 10000 views in all");
  if (o.scales < 1 || o.scales > 8) throw Error("make-scene: --scales must be 1 to 8, got " + std::to_string(o.scales));
  const uint32_t divisor = 1u << (o.scales - 1);
  if (o.size_px % divisor != 0) {
    throw Error("make-scene: --size " + std::to_string(o.size_px) + " is not divisible by " + std::to_string(divisor) +
                " for " + std::to_string(o.scales) + " scales; use a multiple of " + std::to_string(divisor));
  }
  if (o.samples_per_axis < 1 || o.samples_per_axis > 64) throw Error("make-scene: --samples must be 1 to 64");
  if (!(o.camera_angle_x > 0.0 && o.camera_angle_x < 3.0)) throw Error("make-scene: camera_angle_x must be in (0, 3)");
  if (!o.lens.is_pinhole() && o.scales > 1) {
    throw Error("make-scene --lens: the multiscale copy (metadata.json) holds pinhole cameras only; add --scales 1 (train "
                "builds scales of a lens capture on the fly: --set multiscale=true)");
  }
  if (!(o.near >= 0.0 && o.far > o.near)) throw Error("make-scene: need 0 <= near < far");
  // Every pixel must have a ray behind the lens (a fisheye's θ_d = r/f reaches 90° at r = f·π/2 only with its
  // coefficients' help; --fov sets f as for a pinhole).
  if (!o.lens.is_pinhole()) {
    char fov[32];
    std::snprintf(fov, sizeof fov, "%.4g", o.camera_angle_x * 180 / M_PI);
    check_lens_over_image(camera_at({0, 0, 4}, o), std::string("make-scene --lens ") + lens_model_name(o.lens.model) +
                                                        " at --fov " + fov + " (a narrower --fov keeps the image inside the lens)");
  }
}

std::vector<Camera> procedural_cameras(const std::string& split, const SceneOptions& options) {
  const uint32_t index = split_index(split);
  std::vector<Camera> cameras;
  if (index == 0) {
    // Uniform over the spherical cap 10° … 80° elevation: sin(elevation) uniform, azimuth uniform.
    const double z_low = std::sin(10.0 * M_PI / 180.0), z_high = std::sin(80.0 * M_PI / 180.0);
    for (uint32_t v = 0; v < options.train_views; ++v) {
      const auto u = rng_uniform4(options.seed, v, 0, 0, kStreamCameras);
      const double elevation = std::asin(z_low + (z_high - z_low) * u[0]);
      cameras.push_back(camera_at(on_sphere(options.camera_distance, elevation, 2.0 * M_PI * u[1]), options));
    }
  } else {
    const uint32_t count = index == 1 ? options.val_views : options.test_views;
    const double elevation = (index == 1 ? 25.0 : 40.0) * M_PI / 180.0;
    const double phase = rng_uniform4(options.seed, 0, index, 0, kStreamCameras)[0] + (index == 2 ? 0.5 : 0.0);
    for (uint32_t v = 0; v < count; ++v) {
      const double azimuth = 2.0 * M_PI * (v + phase) / count;
      cameras.push_back(camera_at(on_sphere(options.camera_distance, elevation, azimuth), options));
    }
  }
  return cameras;
}

SceneHit trace_procedural(const Ray& ray) {
  SceneHit hit;
  hit.t = 1e300;
  Vec3 rgb{0, 0, 0};
  if (hit_sphere(ray, hit.t, rgb)) hit.hit = true;
  for (const auto& box : kBoxes) {
    if (hit_box(box, ray, hit.t, rgb)) hit.hit = true;
  }
  if (hit.hit) hit.rgb = rgb;
  else hit.t = 0.0;
  return hit;
}

RgbaImage render_procedural(const Camera& camera, const SceneOptions& options, uint32_t view_key) {
  return render_traced(camera, options, view_key, trace_procedural);
}

RgbaImage render_traced(const Camera& camera, const SceneOptions& options, uint32_t view_key,
                        SceneHit (*trace)(const Ray&)) {
  RgbaImage image{camera.width_px, camera.height_px, {}};
  image.rgba.assign(static_cast<size_t>(image.width) * image.height * 4, 0.0f);
  const uint32_t s = options.samples_per_axis;
  const double inv_s = 1.0 / s, inv_n = 1.0 / (s * s);
  for (uint32_t y = 0; y < image.height; ++y) {
    for (uint32_t x = 0; x < image.width; ++x) {
      const uint32_t pixel = y * image.width + x;
      Vec3 sum{0, 0, 0};
      int hits = 0;
      for (uint32_t k = 0; k < s * s; k += 2) {
        // Two jittered samples per Philox call: stratum k and k + 1 of the s × s grid.
        const auto u = rng_uniform4(options.seed, pixel, view_key, k / 2, kStreamJitter);
        for (uint32_t m = 0; m < 2 && k + m < s * s; ++m) {
          const uint32_t stratum = k + m;
          const double sx = x + ((stratum % s) + u[2 * m]) * inv_s;
          const double sy = y + ((stratum / s) + u[2 * m + 1]) * inv_s;
          const SceneHit hit = trace(camera_ray(camera, sx, sy));
          if (hit.hit) {
            sum = add(sum, hit.rgb);
            ++hits;
          }
        }
      }
      float* out = image.rgba.data() + 4 * static_cast<size_t>(pixel);
      for (int c = 0; c < 3; ++c) out[c] = hits ? static_cast<float>(sum[c] / hits) : 0.0f;
      out[3] = static_cast<float>(hits * inv_n);
    }
  }
  return image;
}

Camera centred_pinhole(const std::array<double, 12>& camera_to_world, uint32_t width_px, uint32_t height_px,
                       double angle_x) {
  Camera camera;
  camera.camera_to_world = camera_to_world;
  camera.width_px = width_px;
  camera.height_px = height_px;
  camera.focal_x_px = camera.focal_y_px = 0.5 * width_px / std::tan(0.5 * angle_x);
  camera.center_x_px = 0.5 * width_px;
  camera.center_y_px = 0.5 * height_px;
  return camera;
}

void write_procedural_scene(const std::string& out_dir, const SceneOptions& options, const LogFn& log) {
  validate(options);
  const auto start = std::chrono::steady_clock::now();
  io::make_directories(out_dir);
  const unsigned threads = options.threads ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  for (const char* split : {"train", "val", "test"}) {
    const auto cameras = procedural_cameras(split, options);
    if (cameras.empty()) continue;
    const uint32_t index = split_index(split);
    io::Json frames = io::Json::array();
    for (size_t v = 0; v < cameras.size(); ++v) {
      frames.push_back({{"file_path", "./" + std::string(split) + "/r_" + std::to_string(v)},
                        {"transform_matrix", pose_to_json(cameras[v].camera_to_world)}});
    }
    parallel_for(cameras.size(), threads, [&](size_t v) {
      const RgbaImage image = render_procedural(cameras[v], options, index * 65536u + static_cast<uint32_t>(v));
      io::write_png(out_dir + "/" + split + "/r_" + std::to_string(v) + ".png", image.width, image.height, 4,
                    image.rgba.data(), 8);
    });
    io::Json transforms = lens_json(options.lens);
    transforms.update(io::Json{
        {"camera_angle_x", options.camera_angle_x},
        {"near", options.near},
        {"far", options.far},
        {"generator",
         {{"program", "mipnerf-cl make-scene"},
          {"seed", options.seed},
          {"size", options.size_px},
          {"samples_per_pixel", options.samples_per_axis * options.samples_per_axis}}},
        {"frames", frames}});
    io::write_json(out_dir + "/transforms_" + split + ".json", transforms);
    if (log) log(LogLevel::info, std::string(split) + ": " + std::to_string(cameras.size()) + " views rendered");
  }
  if (options.scales > 1) write_multiscale(out_dir, out_dir + "/multiscale", options.scales, log);
  if (log) {
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    char text[128];
    std::snprintf(text, sizeof(text), "scene written in %.2f s on %u threads", seconds, threads);
    log(LogLevel::info, text);
  }
}

}  // namespace mipnerf::data
