// Render, score and time the views of a split.
#include "eval/evaluate.hpp"

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
  std::map<uint32_t, ScaleSummary> by_scale;
  for (size_t k = 0; k < views.size(); ++k) {
    const size_t i = views[k];
    const RenderedImage image = renderer.render(i);
    const data::Camera& camera = split.cameras[i];
    const ImageView rendered{image.rgb.data(), camera.height_px, camera.width_px, 3};
    const ImageView truth{split.image_rgb(i), camera.height_px, camera.width_px, 3};
    ImageScore score;
    score.index = i;
    score.file = split.files[i];
    score.scale_level = split.scale_levels[i];
    score.width = camera.width_px;
    score.height = camera.height_px;
    score.psnr = psnr(rendered, truth);
    // SSIM's 11×11 window needs images at least that large (×8 downsampled views may be smaller).
    score.ssim = options.ssim && camera.width_px >= 11 && camera.height_px >= 11 ? ssim(rendered, truth) : 0.0;
    score.seconds = image.seconds;
    scores.images.push_back(score);
    scores.render_seconds += image.seconds;
    scores.megapixels += image.megapixels();
    ScaleSummary& s = by_scale[score.scale_level];
    s.scale_level = score.scale_level;
    ++s.images;
    s.mean_psnr += score.psnr;
    s.mean_ssim += score.ssim;
    if (options.on_image) options.on_image(score, image, split.image_rgb(i));
    if (options.progress) options.progress(k + 1, views.size());
  }
  for (auto& [level, s] : by_scale) {
    s.mean_psnr /= static_cast<double>(s.images);
    s.mean_ssim /= static_cast<double>(s.images);
    scores.scales.push_back(s);
  }
  for (const auto& image : scores.images) {
    scores.mean_psnr += image.psnr / static_cast<double>(scores.images.size());
    scores.mean_ssim += image.ssim / static_cast<double>(scores.images.size());
  }
  return scores;
}

}  // namespace mipnerf::eval
