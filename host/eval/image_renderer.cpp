// Whole images through an inference graph, chunk by chunk (and pass by pass when supersampling).
#include "eval/image_renderer.hpp"

#include <chrono>
#include <numeric>

#include "core/error.hpp"
#include "parallel/world.hpp"

namespace mipnerf::eval {
namespace {

graph::GraphMode mode_for(const RenderSettings& settings) {
  return settings.supersample > 1 ? graph::GraphMode::inference_jittered : graph::GraphMode::inference;
}

// The cameras, once each is known to fit the device's 32-bit pixel indices.
const std::vector<Camera>& renderable(const std::vector<Camera>& cameras) {
  if (cameras.empty()) throw Error("render: no camera to render");
  for (const auto& camera : cameras) {
    if (static_cast<uint64_t>(camera.width_px) * camera.height_px > 0xFFFFFFFFull) {
      throw Error("render: an image of " + std::to_string(camera.width_px) + "x" + std::to_string(camera.height_px) +
                  " has more than 2^32 - 1 pixels");
    }
  }
  return cameras;
}

const RenderSettings& checked(const RenderSettings& settings) {
  if (settings.chunk_rays == 0) throw Error("render: the chunk size must be at least one ray");
  if (settings.supersample == 0) throw Error("render: supersampling needs at least one ray per pixel");
  return settings;
}

// The jitter seed of one camera (splitmix64 of seed and index), so views do not share a jitter pattern.
uint64_t camera_seed(uint64_t seed, size_t index) {
  uint64_t z = seed + 0x9E3779B97F4A7C15ull * (static_cast<uint64_t>(index) + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

}  // namespace

ImageRenderer::ImageRenderer(ocl::Context& ctx, const graph::GraphSpec& spec, std::vector<mlp::Network*> networks,
                             const std::vector<Camera>& cameras, size_t chunk_rays)
    : ImageRenderer(ctx, spec, std::move(networks), cameras, RenderSettings{chunk_rays, 1, 0}) {}

ImageRenderer::ImageRenderer(ocl::Context& ctx, const graph::GraphSpec& spec, std::vector<mlp::Network*> networks,
                             const std::vector<Camera>& cameras, const RenderSettings& settings)
    : ImageRenderer(ctx, spec, std::move(networks), {}, cameras, settings) {}

ImageRenderer::ImageRenderer(ocl::Context& ctx, const graph::GraphSpec& spec, std::vector<mlp::Network*> networks,
                             std::vector<mlp::GridTable*> grids, const std::vector<Camera>& cameras,
                             const RenderSettings& settings)
    : ctx_(&ctx),
      cameras_(renderable(cameras)),
      settings_(checked(settings)),
      graph_(ctx, spec, std::move(networks), std::move(grids), mode_for(settings), settings.chunk_rays),
      device_cameras_(ctx, cameras_, {}, "render"),
      camera_ids_(ctx, settings.chunk_rays, "render camera_ids [chunk]"),
      pixel_ids_(ctx, settings.chunk_rays, "render pixel_ids [chunk]") {}

void ImageRenderer::set_cameras(const std::vector<Camera>& cameras) {
  cameras_ = renderable(cameras);
  device_cameras_ = data::DeviceCameras(*ctx_, cameras_, {}, "render");
}

RenderedImage ImageRenderer::render(size_t index, const std::function<void(size_t, size_t)>& progress) {
  if (index >= cameras_.size()) {
    throw Error("render: camera " + std::to_string(index) + " of " + std::to_string(cameras_.size()));
  }
  const auto start = std::chrono::steady_clock::now();
  const Camera& camera = cameras_[index];
  RenderedImage image;
  image.width = camera.width_px;
  image.height = camera.height_px;
  const size_t n_pixels = static_cast<size_t>(image.width) * image.height;
  image.rgb.assign(3 * n_pixels, 0.0f);
  image.depth.assign(n_pixels, 0.0f);
  image.acc.assign(n_pixels, 0.0f);

  camera_ids_.fill(*ctx_, static_cast<uint32_t>(index));
  const size_t chunk_rays = settings_.chunk_rays;
  const uint32_t passes = settings_.supersample;
  std::vector<uint32_t> ids(chunk_rays);
  std::vector<float> rgb, depth, acc;  // one chunk of one pass (supersampling only)
  if (passes > 1) {
    rgb.resize(3 * chunk_rays);
    depth.resize(chunk_rays);
    acc.resize(chunk_rays);
  }
  const graph::RaySource source{device_cameras_, camera_ids_, pixel_ids_};
  const auto& out = graph_.level_outputs(graph_.spec().levels.size() - 1);
  const uint64_t seed = camera_seed(settings_.seed, index);
  // Under mpirun each rank renders a contiguous share of the image's chunks (whole chunks, so every pixel is
  // computed as in a single-process render), then the shares are gathered; one rank renders them all.
  const parallel::World& world = parallel::world();
  std::vector<size_t> pixel_shares = parallel::share_offsets((n_pixels + chunk_rays - 1) / chunk_rays, world.size());
  for (size_t& offset : pixel_shares) offset = std::min(n_pixels, offset * chunk_rays);  // chunks → pixels
  const size_t my_begin = pixel_shares[static_cast<size_t>(world.rank())];
  const size_t my_end = pixel_shares[static_cast<size_t>(world.rank()) + 1];
  const size_t total_rays = n_pixels * passes;
  // Progress counts this rank's share, scaled to the image: the ranks advance together.
  const double progress_scale = my_end > my_begin ? static_cast<double>(n_pixels) / (my_end - my_begin) : 1.0;
  auto report = [&](size_t rays) {
    if (progress) progress(std::min(total_rays, static_cast<size_t>(rays * progress_scale)), total_rays);
  };
  size_t done_rays = 0;
  for (size_t first = my_begin; first < my_end; first += chunk_rays) {
    const size_t count = std::min(chunk_rays, my_end - first);
    std::iota(ids.begin(), ids.begin() + static_cast<long>(count), static_cast<uint32_t>(first));
    pixel_ids_.upload(*ctx_, ids.data(), count);
    if (passes == 1) {
      graph_.render_chunk(source, {0, count});
      out.comp_rgb.download(*ctx_, image.rgb.data() + 3 * first, 3 * count);
      out.distance.download(*ctx_, image.depth.data() + first, count);
      out.acc.download(*ctx_, image.acc.data() + first, count);
    } else {
      // Pass p jitters pixel q with Philox(seed, q, p): the ray number is the pixel's index in the image.
      for (uint32_t pass = 0; pass < passes; ++pass) {
        graph_.render_chunk(source, {0, count}, {seed, pass}, static_cast<uint32_t>(first));
        out.comp_rgb.download(*ctx_, rgb.data(), 3 * count);
        out.distance.download(*ctx_, depth.data(), count);
        out.acc.download(*ctx_, acc.data(), count);
        for (size_t k = 0; k < 3 * count; ++k) image.rgb[3 * first + k] += rgb[k] / static_cast<float>(passes);
        for (size_t k = 0; k < count; ++k) {
          image.depth[first + k] += depth[k] / static_cast<float>(passes);
          image.acc[first + k] += acc[k] / static_cast<float>(passes);
        }
        if (pass + 1 < passes) report(done_rays + (pass + 1) * count);
      }
    }
    done_rays += count * passes;
    report(done_rays);
  }
  if (world.distributed()) gather_shares(image, pixel_shares);
  image.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return image;
}

void ImageRenderer::gather_shares(RenderedImage& image, const std::vector<size_t>& pixel_shares) {
  std::vector<size_t> rgb_shares = pixel_shares;
  for (size_t& offset : rgb_shares) offset *= 3;
  const parallel::World& world = parallel::world();
  world.all_gather_segments(image.rgb.data(), rgb_shares);
  world.all_gather_segments(image.depth.data(), pixel_shares);
  world.all_gather_segments(image.acc.data(), pixel_shares);
}

double ImageRenderer::warm_up() {
  const auto start = std::chrono::steady_clock::now();
  const Camera& camera = cameras_.front();
  const size_t count = std::min(settings_.chunk_rays, static_cast<size_t>(camera.width_px) * camera.height_px);
  std::vector<uint32_t> ids(count);
  std::iota(ids.begin(), ids.end(), 0u);
  camera_ids_.fill(*ctx_, 0u);
  pixel_ids_.upload(*ctx_, ids.data(), count);
  graph_.render_chunk({device_cameras_, camera_ids_, pixel_ids_},
                      {0, count}, {settings_.seed, 0}, 0);
  std::vector<float> acc(count);
  graph_.level_outputs(graph_.spec().levels.size() - 1).acc.download(*ctx_, acc.data(), count);  // waits
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace mipnerf::eval
