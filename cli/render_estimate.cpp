// The frames, size and time estimate `render` prints before its first frame.
#include "render_estimate.hpp"

#include <algorithm>
#include <cstdio>

#include "core/duration.hpp"
#include "eval/report.hpp"
#include "io/json.hpp"

namespace mipnerf::cli {

std::optional<RecordedRate> recorded_rate(const std::string& run_folder, const std::string& device) {
  const std::optional<io::Json> summary = eval::read_summary(run_folder);
  if (!summary) return std::nullopt;
  try {
    const io::Json val = summary->value("val", io::Json::object());
    const double rate = val.value("render_seconds_per_megapixel", 0.0);
    if (summary->value("device", std::string()) != device || !(rate > 0.0)) return std::nullopt;
    return RecordedRate{rate, "the run's val renders on this device, " + eval::summary_path(run_folder)};
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

RenderEstimate::RenderEstimate(const std::vector<Camera>& cameras, uint32_t rays_per_pixel,
                               std::optional<RecordedRate> rate, bool path_frames)
    : frames_(cameras.size()),
      megapixels_(0.0),
      first_frame_rays_(cameras.empty() ? 0 : size_t{cameras[0].width_px} * cameras[0].height_px * rays_per_pixel),
      rays_per_pixel_(rays_per_pixel),
      rate_(std::move(rate)),
      path_frames_(path_frames) {
  uint64_t smallest = UINT64_MAX, largest = 0;
  std::string smallest_text, largest_text;
  for (const Camera& c : cameras) {
    const uint64_t pixels = uint64_t{c.width_px} * c.height_px;
    megapixels_ += static_cast<double>(pixels) * rays_per_pixel / 1e6;
    const std::string text = std::to_string(c.width_px) + "x" + std::to_string(c.height_px);
    if (pixels < smallest) smallest = pixels, smallest_text = text;
    if (pixels > largest) {
      largest = pixels, largest_text = text;
      largest_width_ = c.width_px, largest_height_ = c.height_px;
    }
  }
  size_text_ = smallest_text == largest_text ? smallest_text : smallest_text + " to " + largest_text;
}

std::string RenderEstimate::opening_line() const {
  char head[160];
  std::snprintf(head, sizeof(head), "rendering %zu frame%s of %s (%.3g MP%s)", frames_, frames_ == 1 ? "" : "s",
                size_text_.c_str(), megapixels_,
                rays_per_pixel_ > 1 ? (" of rays, " + std::to_string(rays_per_pixel_) + " per pixel").c_str() : "");
  if (!rate_) return std::string(head) + ": the time it takes follows its first frame";
  char rate[64];
  std::snprintf(rate, sizeof(rate), "%.3g s/MP", rate_->seconds_per_megapixel);
  const double seconds = rate_->seconds_per_megapixel * megapixels_;
  return std::string(head) + ": about " + format_duration(seconds) + " at " + rate + " (" + rate_->source + ")" +
         shorter_hint(seconds);
}

// Where a path's render will take more than five minutes: what about half its width and height would take (a
// quarter of the rays), e.g. a spiral of a phone capture on a CPU (120 full-size frames, 20 minutes and more).
std::string RenderEstimate::shorter_hint(double seconds) const {
  constexpr double kLongSeconds = 300.0;
  if (!path_frames_ || seconds <= kLongSeconds || largest_width_ < 16 || largest_height_ < 16) return "";
  // Even, as --video's H.264 (4:2:0) needs: 504x378 becomes 252x188, not 252x189.
  const uint32_t width = (largest_width_ / 2) & ~1u, height = (largest_height_ / 2) & ~1u;
  return "; --size " + std::to_string(width) + "x" + std::to_string(height) + " would take about " +
         format_duration(seconds * (double(width) * height) / (double(largest_width_) * largest_height_)) +
         ", fewer --frames less";
}

std::string RenderEstimate::report(size_t rays_done) {
  const auto now = std::chrono::steady_clock::now();
  if (!start_) {
    start_ = now;
    return opening_line();
  }
  if (rate_ || first_frame_told_ || frames_ < 2 || first_frame_rays_ == 0 || rays_done < first_frame_rays_) return "";
  first_frame_told_ = true;
  const double seconds = std::chrono::duration<double>(now - *start_).count();
  const double per_megapixel = seconds / (static_cast<double>(first_frame_rays_) / 1e6);
  char text[160];
  std::snprintf(text, sizeof(text), "the first frame took %.3g s (%.3g s/MP): about %s for all %zu frames", seconds,
                per_megapixel, format_duration(per_megapixel * megapixels_).c_str(), frames_);
  return text;
}

}  // namespace mipnerf::cli
