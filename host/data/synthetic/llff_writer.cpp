// The LLFF writer of the built-in traced captures.
#include "data/synthetic/llff_writer.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <thread>

#include "data/image.hpp"
#include "io/file.hpp"
#include "io/jpeg.hpp"
#include "io/npy.hpp"
#include "io/png.hpp"

namespace mipnerf::data {
namespace {

void write_rgb(const std::string& path, const RgbaImage& image, bool jpeg) {
  std::vector<float> rgb(static_cast<size_t>(image.width) * image.height * 3);
  for (size_t p = 0; p < rgb.size() / 3; ++p) {
    for (int c = 0; c < 3; ++c) rgb[3 * p + c] = image.rgba[4 * p + c];
  }
  if (jpeg) {
    io::write_jpeg(path, image.width, image.height, rgb.data(), 95);
  } else {
    io::write_png(path, image.width, image.height, 3, rgb.data(), 8);
  }
}

}  // namespace

std::vector<double> traced_depths(const Camera& camera, SceneHit (*trace)(const Ray&)) {
  std::vector<double> depths;
  for (int j = 0; j < 24; ++j) {
    for (int i = 0; i < 32; ++i) {
      const SceneHit hit =
          trace(camera_ray(camera, (i + 0.5) * camera.width_px / 32.0, (j + 0.5) * camera.height_px / 24.0));
      if (hit.hit && std::isfinite(hit.t)) depths.push_back(hit.t);
    }
  }
  std::sort(depths.begin(), depths.end());
  return depths;
}

std::string llff_image_name(size_t k, bool jpeg) {
  char name[32];
  std::snprintf(name, sizeof(name), "image%03zu.%s", k, jpeg ? "jpg" : "png");
  return name;
}

void write_view_images(const std::string& out_dir, const std::vector<Camera>& cameras, SceneHit (*trace)(const Ray&),
                       const LlffWriteOptions& options) {
  const std::string full = out_dir + "/images", reduced = out_dir + "/images_" + std::to_string(options.factor);
  io::make_directories(full);
  if (options.factor > 1) io::make_directories(reduced);
  SceneOptions render;
  render.seed = options.seed;
  render.samples_per_axis = options.samples_per_axis;
  const unsigned threads = options.threads ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  std::atomic<size_t> next{0};
  auto worker = [&] {
    for (size_t k = next++; k < cameras.size(); k = next++) {
      RgbaImage image = render_traced(cameras[k], render, options.view_key_base + static_cast<uint32_t>(k), trace);
      write_rgb(full + "/" + llff_image_name(k, options.jpeg), image, options.jpeg);
      for (uint32_t f = 1; f < options.factor; f *= 2) image = downsample2(image);
      if (options.factor > 1) write_rgb(reduced + "/" + llff_image_name(k, options.jpeg), image, options.jpeg);
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& thread : pool) thread.join();
}

void write_llff_views(const std::string& out_dir, const std::vector<Camera>& cameras, SceneHit (*trace)(const Ray&),
                      const LlffWriteOptions& options) {
  write_view_images(out_dir, cameras, trace, options);
  // poses_bounds.npy: per view the 3×5 [down, right, backwards, position, (h, w, focal)] of LLFF, then near, far.
  std::vector<double> rows;
  for (const auto& camera : cameras) {
    const auto& m = camera.camera_to_world;
    const double hwf[3] = {static_cast<double>(camera.height_px), static_cast<double>(camera.width_px), camera.focal_x_px};
    for (int r = 0; r < 3; ++r) {
      for (double value : {-m[4 * r + 1], m[4 * r + 0], m[4 * r + 2], m[4 * r + 3], hwf[r]}) rows.push_back(value);
    }
    rows.push_back(camera.near);
    rows.push_back(camera.far);
  }
  io::write_npy(out_dir + "/poses_bounds.npy", rows, {cameras.size(), 17});
}

}  // namespace mipnerf::data
