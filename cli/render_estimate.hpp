// What `render` says before its first frame: how many frames, their size, and about how long they will take — from
// the run's own val renders on this device (RUN/summary.json), else measured on the first frame and said then.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.hpp"

namespace mipnerf::cli {

// A rate recorded by an earlier render of the same model: seconds per megapixel and where it comes from.
struct RecordedRate {
  double seconds_per_megapixel = 0.0;
  std::string source;  // "the run's val renders on this device (RUN/summary.json)"
};

// The val renders' s/MP in RUN/summary.json when they ran on `device`; none without the file, its val section, or
// when another device rendered them (its rate would mislead), or when the file cannot be read (no estimate is worth
// failing a render for).
std::optional<RecordedRate> recorded_rate(const std::string& run_folder, const std::string& device);

class RenderEstimate {
 public:
  // path_frames: the cameras are a path's (orbit, spiral, a path file), whose --size and --frames the user chooses;
  // an estimate over five minutes then says what half the size would take.
  RenderEstimate(const std::vector<Camera>& cameras, uint32_t rays_per_pixel, std::optional<RecordedRate> rate,
                 bool path_frames = false);

  // Fed the job's progress (rays done), returns the line to print now, if any. The first call (the job's first
  // report, once the device is ready) starts the clock and returns "rendering 120 frames of 1008x756 (91.4 MP): about
  // 33m40s at 22.1 s/MP (the run's val renders on this device, RUN/summary.json)", or "rendering …: the time it takes
  // follows its first frame" where no rate was recorded; then, in that case and where more frames follow, once the
  // first frame is done: "the first frame took 16.8 s (0.18 s/MP): about 33m20s for all 120 frames".
  std::string report(size_t rays_done);

 private:
  size_t frames_;
  double megapixels_;  // every frame, each ray of a pixel counted (supersampling multiplies the work)
  size_t first_frame_rays_;
  std::string size_text_;
  uint32_t rays_per_pixel_;
  std::optional<RecordedRate> rate_;
  bool path_frames_;
  uint32_t largest_width_ = 0, largest_height_ = 0;
  std::optional<std::chrono::steady_clock::time_point> start_;
  bool first_frame_told_ = false;

  std::string opening_line() const;
  std::string shorter_hint(double seconds) const;
};

}  // namespace mipnerf::cli
