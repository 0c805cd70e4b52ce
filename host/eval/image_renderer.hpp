// Rendering whole images from trained networks: every pixel of a camera through an inference graph, in
// chunks whose size bounds device memory, with the colour, expected depth and accumulation of the last level;
// optionally K jittered rays per pixel averaged (supersampling).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "core/camera.hpp"
#include "data/device_cameras.hpp"
#include "graph/graph.hpp"

namespace mipnerf::eval {

struct RenderedImage {
  uint32_t width = 0, height = 0;
  std::vector<float> rgb;    // [height][width][3], the training images' space (sRGB-encoded values in [0, 1])
  std::vector<float> depth;  // [height][width] expected distance along the ray, in t (depth along the optical axis)
  std::vector<float> acc;    // [height][width] accumulated opacity
  double seconds = 0.0;      // wall time of the render, device work included
  double megapixels() const { return static_cast<double>(width) * height / 1e6; }
};

struct RenderSettings {
  size_t chunk_rays = 4096;  // rays per launch sequence: bounds the device memory, whatever the image size
  // Rays per pixel. 1: one ray through the pixel's centre offset (the model's pixel_center), deterministic.
  // K > 1: K rays through uniformly random points of the pixel (a new Philox draw per pass, keyed by seed,
  // camera, pass and pixel, so independent of the chunking), their colour, depth and accumulation averaged: the
  // jittered supersampling baseline of the paper's supplement. Cone radii stay those of the whole pixel.
  uint32_t supersample = 1;
  uint64_t seed = 0;  // of the supersampling jitter
};

class ImageRenderer {
 public:
  // `cameras` are uploaded once; chunk_rays bounds the rays (and so the memory) of one launch sequence.
  ImageRenderer(ocl::Context& ctx, const graph::GraphSpec& spec, std::vector<mlp::Network*> networks,
                const std::vector<Camera>& cameras, size_t chunk_rays);
  ImageRenderer(ocl::Context& ctx, const graph::GraphSpec& spec, std::vector<mlp::Network*> networks,
                const std::vector<Camera>& cameras, const RenderSettings& settings);
  // With Zip-NeRF's grids (spec.grids; they outlive the renderer).
  ImageRenderer(ocl::Context& ctx, const graph::GraphSpec& spec, std::vector<mlp::Network*> networks,
                std::vector<mlp::GridTable*> grids, const std::vector<Camera>& cameras, const RenderSettings& settings);

  // Replaces the cameras (uploaded once more; the graph and its buffers stay): the viewer renders each request's
  // camera through one renderer instead of building a graph per request.
  void set_cameras(const std::vector<Camera>& cameras);

  // Renders camera `index`; `progress(done_rays, total_rays)` is called after every chunk (total_rays counts
  // every supersampling pass).
  RenderedImage render(size_t index, const std::function<void(size_t, size_t)>& progress = {});

  // Runs one chunk of camera 0 and waits for it, outside any timing: first-use costs (kernel builds, CLBlast's
  // program compilation, driver warm-up) then stay out of the render seconds. Returns its wall time.
  double warm_up();

  size_t chunk_rays() const { return settings_.chunk_rays; }
  const RenderSettings& settings() const { return settings_; }
  const std::vector<Camera>& cameras() const { return cameras_; }

 private:
  // Under mpirun: every rank receives the pixels the others rendered (rank r rendered the pixels
  // [pixel_shares[r], pixel_shares[r + 1])).
  static void gather_shares(RenderedImage& image, const std::vector<size_t>& pixel_shares);

  ocl::Context* ctx_;
  std::vector<Camera> cameras_;
  RenderSettings settings_;
  graph::Graph graph_;
  data::DeviceCameras device_cameras_;     // packed, with their lens tables
  ocl::DeviceArray<uint32_t> camera_ids_;  // [chunk]
  ocl::DeviceArray<uint32_t> pixel_ids_;   // [chunk]
};

}  // namespace mipnerf::eval
