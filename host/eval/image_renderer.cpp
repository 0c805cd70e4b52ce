// Whole images through an inference graph, chunk by chunk.
#include "eval/image_renderer.hpp"

#include <chrono>
#include <numeric>

#include "cl/error.hpp"

namespace mipnerf::eval {

ImageRenderer::ImageRenderer(ocl::Context& ctx, const graph::GraphSpec& spec, std::vector<mlp::Mlp*> networks,
                             const std::vector<data::Camera>& cameras, size_t chunk_rays)
    : ctx_(&ctx),
      cameras_(cameras),
      chunk_rays_(chunk_rays),
      graph_(ctx, spec, std::move(networks), graph::GraphMode::inference, chunk_rays),
      packed_cameras_(ctx, std::max<size_t>(1, cameras.size()) * data::camera_layout::stride, "render cameras [C][24]"),
      camera_ids_(ctx, chunk_rays, "render camera_ids [chunk]"),
      pixel_ids_(ctx, chunk_rays, "render pixel_ids [chunk]") {
  if (cameras_.empty()) throw Error("render: no camera to render");
  packed_cameras_.upload(ctx, data::pack_cameras(cameras_));
}

RenderedImage ImageRenderer::render(size_t index, const std::function<void(size_t, size_t)>& progress) {
  if (index >= cameras_.size()) {
    throw Error("render: camera " + std::to_string(index) + " of " + std::to_string(cameras_.size()));
  }
  const auto start = std::chrono::steady_clock::now();
  const data::Camera& camera = cameras_[index];
  RenderedImage image;
  image.width = camera.width_px;
  image.height = camera.height_px;
  const size_t n_pixels = static_cast<size_t>(image.width) * image.height;
  image.rgb.resize(3 * n_pixels);
  image.depth.resize(n_pixels);
  image.acc.resize(n_pixels);

  camera_ids_.fill(*ctx_, static_cast<uint32_t>(index));
  std::vector<uint32_t> ids(chunk_rays_);
  const graph::RaySource source{packed_cameras_, camera_ids_, pixel_ids_};
  const auto& out = graph_.level_outputs(graph_.spec().levels.size() - 1);
  for (size_t first = 0; first < n_pixels; first += chunk_rays_) {
    const size_t count = std::min(chunk_rays_, n_pixels - first);
    std::iota(ids.begin(), ids.begin() + static_cast<long>(count), static_cast<uint32_t>(first));
    pixel_ids_.upload(*ctx_, ids.data(), count);
    graph_.render_chunk(source, {0, count});
    out.comp_rgb.download(*ctx_, image.rgb.data() + 3 * first, 3 * count);
    out.distance.download(*ctx_, image.depth.data() + first, count);
    out.acc.download(*ctx_, image.acc.data() + first, count);
    if (progress) progress(first + count, n_pixels);
  }
  image.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return image;
}

}  // namespace mipnerf::eval
