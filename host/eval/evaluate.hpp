// Evaluating trained networks on a split: render each view, score it against its ground truth (PSNR and
// SSIM as the paper's code), and time it — every accuracy figure comes with what it cost.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "data/dataset.hpp"
#include "eval/image_renderer.hpp"

namespace mipnerf::eval {

struct ImageScore {
  size_t index = 0;          // image of the split
  std::string file;          // its ground-truth PNG
  uint32_t scale_level = 0;  // 0 = full resolution, j = downsampled by 2^j
  uint32_t width = 0, height = 0;
  double psnr = 0.0;
  double ssim = 0.0;      // 0 when has_ssim is false
  bool has_ssim = false;  // SSIM computed: asked for, and the image at least as large as the 11×11 window
  double seconds = 0.0;   // render wall time
};

struct ScaleSummary {
  uint32_t scale_level = 0;
  uint32_t width = 0, height = 0;  // of the scale's first image
  size_t images = 0;
  size_t ssim_images = 0;  // images with an SSIM (see ImageScore::has_ssim)
  double mean_psnr = 0.0;  // mean of per-image PSNRs (the official eval's average)
  double mean_ssim = 0.0;  // mean over the ssim_images; NaN when there are none
  double render_seconds = 0.0;
  double megapixels = 0.0;
  double seconds_per_megapixel() const { return megapixels > 0 ? render_seconds / megapixels : 0.0; }
};

struct SplitScores {
  std::vector<ImageScore> images;
  std::vector<ScaleSummary> scales;  // by increasing scale level
  double mean_psnr = 0.0;            // over all images
  double mean_ssim = 0.0;            // over the images with an SSIM; NaN when there are none
  size_t ssim_images = 0;
  double render_seconds = 0.0;
  double megapixels = 0.0;
  double seconds_per_megapixel() const { return megapixels > 0 ? render_seconds / megapixels : 0.0; }
};

struct EvaluateOptions {
  size_t max_views = 0;  // 0: every image of the split; n: the first n full-resolution views (all their scales)
  bool ssim = true;
  // Called with each rendered image and its score (e.g. to write PNG/EXR outputs).
  std::function<void(const ImageScore&, const RenderedImage&, const float* ground_truth_rgb)> on_image;
  std::function<void(size_t done_images, size_t total_images)> progress;
  // Called after every chunk with the rays rendered so far and the total, over all selected images and passes.
  std::function<void(size_t done_rays, size_t total_rays)> ray_progress;
};

// Indices of the split's images that max_views selects (all scales of the first max_views views).
std::vector<size_t> select_views(const data::Split& split, size_t max_views);

// `renderer` must have been built with the split's cameras, in order.
SplitScores evaluate_split(ImageRenderer& renderer, const data::Split& split, const EvaluateOptions& options);

}  // namespace mipnerf::eval
