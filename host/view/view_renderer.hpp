// The viewer's renders on the run's device: the newest checkpoint of the run that loads (reloaded when `train` writes
// a newer one), one image per request at 1/divisor of the page's camera size, each a full mip-NeRF render at that
// resolution (the cone radii follow the pixel size). Newest request wins: a render checks the page's request counter
// after every chunk of rays and stops when a newer request has arrived. One render runs at a time on the device;
// at most `max_waiting` more wait for it, others are answered "busy".
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "cl/context.hpp"
#include "data/camera_path.hpp"
#include "eval/render_job.hpp"
#include "eval/view_cameras.hpp"
#include "train/checkpoint.hpp"
#include "view/handler.hpp"

namespace mipnerf::view {

struct ViewRendererOptions {
  std::string run_folder;
  size_t chunk_rays = 0;   // 0: the device's render chunk (eval::render_chunk_rays), as `render` uses
  size_t max_waiting = 4;  // requests waiting for the device beyond the one rendering
  uint64_t max_pixels = 4096ull * 4096ull;  // per image
};

class ViewRenderer : public RenderBackend {
 public:
  // Loads the run's newest checkpoint that loads and renders one small image, so kernel builds are done before the
  // first request. Throws mipnerf::Error when the run has no checkpoint that loads.
  ViewRenderer(ocl::Context& ctx, ViewRendererOptions options);
  ~ViewRenderer() override;

  RenderReply render(const RenderRequest& request) override;
  // {"train": [frames of the training split, camera-path form], "spiral": [frames], "orbit": {"target", "up",
  //  "radius", "elevation_deg", "frame"}, "start": {"view": "train" | "orbit", "index", "why"}}: the cameras the
  //  page's camera can start from, and the one it starts from (a forward-facing capture: its first training camera).
  std::string cameras_json() override;
  // {"device", "step", "checkpoint", "warm_up_seconds"}
  std::string status_json() override;
  std::string render_progress_json() override;

  // A recorded path renders into RUN/view_paths/path_<UTC time>/ (frame_NNNN.png, transforms.json, render.json and,
  // in a build with video, path.mp4) on a thread of its own, holding the device frame after frame; meanwhile the free
  // camera's renders answer "busy" with the path's progress.
  PathReply start_path(const PathRequest& request) override;
  std::string path_status_json() override;
  void cancel_path() override;

  int64_t step() const;

 private:
  struct PathStatus {
    std::string state = "idle";  // idle | rendering | done | failed | cancelled
    size_t frames_done = 0, frames = 0;
    double seconds = 0.0, eta_seconds = 0.0;
    std::string folder, video, first_frame, message;  // run-relative paths
  };
  void reload_if_newer();  // with device_mutex_ held
  void render_path(eval::ViewFrames frames, std::string folder, eval::VideoOutput video);  // the path thread

  ocl::Context* ctx_;
  ViewRendererOptions options_;
  mutable std::mutex device_mutex_;  // the model and the device's queue
  std::unique_ptr<train::TrainedModel> model_;
  mutable std::mutex info_mutex_;  // what status_json reports, so it never waits for a render
  std::string checkpoint_;
  int64_t step_ = 0;
  std::string cameras_json_;
  data::CameraPathDefaults camera_defaults_;  // what the page's camera may leave out (eval::camera_path_defaults)
  size_t chunk_rays_ = 0;
  double warm_up_seconds_ = 0.0;
  std::atomic<uint64_t> newest_generation_{0};
  // The render under way or the last one (render_progress_json): written by the rendering thread, read by any.
  std::atomic<bool> progress_rendering_{false};
  std::atomic<uint64_t> progress_generation_{0};
  std::atomic<int> progress_divisor_{0};
  std::atomic<size_t> progress_done_{0}, progress_total_{0};
  std::atomic<int64_t> progress_started_ns_{0}, progress_ended_ns_{0};  // steady_clock
  std::atomic<size_t> waiting_{0};
  std::mutex path_start_mutex_;  // held by start_path from its check to storing path_thread_
  std::thread path_thread_;
  std::atomic<bool> path_running_{false};  // from a start's claim until its path thread's last step
  std::atomic<bool> path_cancel_{false};
  mutable std::mutex path_mutex_;  // path_status_
  PathStatus path_status_;
};

}  // namespace mipnerf::view
