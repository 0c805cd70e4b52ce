// Rendering whole images from trained networks: every pixel of a camera through an inference graph, in
// chunks whose size bounds device memory, with the colour, expected depth and accumulation of the last level.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "data/camera.hpp"
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

class ImageRenderer {
 public:
  // `cameras` are uploaded once; chunk_rays bounds the rays (and so the memory) of one launch sequence.
  ImageRenderer(ocl::Context& ctx, const graph::GraphSpec& spec, std::vector<mlp::Mlp*> networks,
                const std::vector<data::Camera>& cameras, size_t chunk_rays);

  // Renders camera `index`; `progress(done_rays, total_rays)` is called after every chunk.
  RenderedImage render(size_t index, const std::function<void(size_t, size_t)>& progress = {});

  size_t chunk_rays() const { return chunk_rays_; }

 private:
  ocl::Context* ctx_;
  std::vector<data::Camera> cameras_;
  size_t chunk_rays_;
  graph::Graph graph_;
  ocl::DeviceArray<float> packed_cameras_;     // [C][24]
  ocl::DeviceArray<uint32_t> camera_ids_;      // [chunk]
  ocl::DeviceArray<uint32_t> pixel_ids_;       // [chunk]
};

}  // namespace mipnerf::eval
