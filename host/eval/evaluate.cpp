// Render, score and time the views of a split.
#include "eval/evaluate.hpp"

#include <cmath>
#include <limits>
#include <map>

#include "eval/metrics.hpp"

namespace mipnerf::eval {

std::vector<size_t> select_views(const data::Split& split, size_t max_views) {
  std::vector<size_t> chosen;
  size_t full_resolution_seen = 0;
  for (size_t i = 0; i < split.num_images(); ++i) {
    // Multiscale splits list a view's scales one after another, the full-resolution image first.
    if (split.scale_levels[i] == 0) ++full_resolution_seen;
    if (max_views == 0 || full_resolution_seen <= max_views) chosen.push_back(i);
  }
  return chosen;
}

SplitScores evaluate_split(ImageRenderer& renderer, const data::Split& split, const EvaluateOptions& options) {
  SplitScores scores;
  const auto views = select_views(split, options.max_views);
  const size_t passes = renderer.settings().supersample;
  size_t total_rays = 0, rays_before = 0;
  for (size_t i : views)
    total_rays += static_cast<size_t>(split.cameras[i].width_px) * split.cameras[i].height_px * passes;
  std::map<uint32_t, ScaleSummary> by_scale;
  for (size_t k = 0; k < views.size(); ++k) {
    const size_t i = views[k];
    std::function<void(size_t, size_t)> on_chunk;
    if (options.ray_progress) {
      on_chunk = [&](size_t done, size_t) { options.ray_progress(rays_before + done, total_rays); };
    }
    const RenderedImage image = renderer.render(i, on_chunk);
    const Camera& camera = split.cameras[i];
    rays_before += static_cast<size_t>(camera.width_px) * camera.height_px * passes;
    const ImageView rendered{image.rgb.data(), camera.height_px, camera.width_px, 3};
    const ImageView truth{split.image_rgb(i), camera.height_px, camera.width_px, 3};
    ImageScore score;
    score.index = i;
    score.file = split.files[i];
    score.scale_level = split.scale_levels[i];
    score.width = camera.width_px;
    score.height = camera.height_px;
    score.psnr = psnr(rendered, truth);
    // SSIM's 11×11 window needs images at least that large (×8 downsampled views may be smaller); such images
    // have no SSIM rather than a made-up one, and the means leave them out.
    const size_t window = SsimOptions{}.filter_size;
    score.has_ssim = options.ssim && camera.width_px >= window && camera.height_px >= window;
    score.ssim = score.has_ssim ? ssim(rendered, truth) : 0.0;
    score.seconds = image.seconds;
    scores.images.push_back(score);
    scores.render_seconds += image.seconds;
    scores.megapixels += image.megapixels();
    ScaleSummary& s = by_scale[score.scale_level];
    if (s.images == 0) {
      s.scale_level = score.scale_level;
      s.width = score.width;
      s.height = score.height;
    }
    ++s.images;
    s.mean_psnr += score.psnr;
    if (score.has_ssim) {
      ++s.ssim_images;
      s.mean_ssim += score.ssim;
    }
    s.render_seconds += image.seconds;
    s.megapixels += image.megapixels();
    if (options.on_image) options.on_image(score, image, split.image_rgb(i));
    if (options.progress) options.progress(k + 1, views.size());
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (auto& [level, s] : by_scale) {
    s.mean_psnr /= static_cast<double>(s.images);
    s.mean_ssim = s.ssim_images ? s.mean_ssim / static_cast<double>(s.ssim_images) : nan;
    scores.scales.push_back(s);
  }
  for (const auto& image : scores.images) {
    scores.mean_psnr += image.psnr / static_cast<double>(scores.images.size());
    if (image.has_ssim) {
      scores.mean_ssim += image.ssim;
      ++scores.ssim_images;
    }
  }
  scores.mean_ssim = scores.ssim_images ? scores.mean_ssim / static_cast<double>(scores.ssim_images) : nan;
  return scores;
}

}  // namespace mipnerf::eval
