// Helpers of the tests/official suite shared by its dataset and model tests: our ray kernel over every pixel of a set
// of cameras, the norms the ray bounds are written in, and the official multiscale (Multicam) scene of
// multicam.json written back to disk.
#pragma once

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "io/json.hpp"
#include "io/png.hpp"
#include "official_fixtures.hpp"
#include "ops/ray_bundle.hpp"
#include "ops/rays.hpp"
#include "support/test_context.hpp"

namespace mipnerf::official {

struct RayArrays {
  std::vector<float> origins, directions, viewdirs, radii, near, far, lossmult;
};

// Our rays for every pixel of every camera, camera-major then row-major (the official [C][H][W] order, and its
// all_images flattening when the cameras differ in size).
inline RayArrays run_rays(const std::vector<Camera>& cameras, const RaysOptions& options) {
  auto& ctx = test::test_context();
  std::vector<uint32_t> camera_ids, pixel_ids;
  for (size_t c = 0; c < cameras.size(); ++c) {
    for (uint32_t p = 0; p < cameras[c].width_px * cameras[c].height_px; ++p) {
      camera_ids.push_back(static_cast<uint32_t>(c));
      pixel_ids.push_back(p);
    }
  }
  const size_t n = camera_ids.size();
  auto packed = upload(ctx, pack_cameras(cameras), "cameras [C][24]");
  auto ids = upload(ctx, camera_ids, "camera_ids [R]");
  auto pixels = upload(ctx, pixel_ids, "pixel_ids [R]");
  ops::RayBundle rays(ctx, n);
  ops::Rays(ctx, options).fwd({packed, ids, pixels, n}, rays);
  return {rays.origins.download(ctx), rays.directions.download(ctx), rays.viewdirs.download(ctx),
          rays.radii.download(ctx),   rays.near.download(ctx),       rays.far.download(ctx),
          rays.lossmult.download(ctx)};
}

// The L1 and L2 norms of the 3-vector holding element i of a [..][3] array.
inline double norm1_at(const std::vector<double>& v, size_t i) {
  const size_t base = 3 * (i / 3);
  return std::abs(v[base]) + std::abs(v[base + 1]) + std::abs(v[base + 2]);
}
inline double norm2_at(const std::vector<double>& v, size_t i) {
  const size_t base = 3 * (i / 3);
  return std::sqrt(v[base] * v[base] + v[base + 1] * v[base + 1] + v[base + 2] * v[base + 2]);
}

// The multiscale scene of multicam.json written again into `dir`: metadata.json as the official converter writes it
// and images_train/<view>_d<scale>.png, byte for byte the same images.
inline void write_multicam_scene(const io::Json& inputs, const std::string& dir) {
  const auto& meta = inputs.at("metadata").at("train");
  const auto& files = meta.at("file_path");
  for (size_t i = 0; i < files.size(); ++i) {
    const uint32_t w = meta.at("width").at(i).get<uint32_t>(), h = meta.at("height").at(i).get<uint32_t>();
    const auto rgba = flat(inputs.at("rgba8").at(i), {h, w, 4});
    const std::vector<uint8_t> bytes(rgba.begin(), rgba.end());
    const auto path = std::filesystem::path(dir) / files.at(i).get<std::string>();
    std::filesystem::create_directories(path.parent_path());
    io::write_png8(path.string(), w, h, 4, bytes.data());
  }
  io::write_json(dir + "/metadata.json", inputs.at("metadata"));
}

}  // namespace mipnerf::official
