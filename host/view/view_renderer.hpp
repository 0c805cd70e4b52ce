// The viewer's renders on the run's device: the newest checkpoint of the run that loads (reloaded when `train` writes
// a newer one), one image per request at 1/divisor of the page's camera size, each a full mip-NeRF render at that
// resolution (the cone radii follow the pixel size). Newest request wins: a render checks the page's request counter
// after every chunk of rays and stops when a newer request has arrived. One render runs at a time on the device;
// at most `max_waiting` more wait for it, others are answered "busy". One image renderer (its inference graph and
// device buffers) serves every request while the checkpoint stays the same; a newer checkpoint gets a new one.
// A recorded path renders in the background (view/path_job) and holds the device meanwhile.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

#include "cl/context.hpp"
#include "data/paths/camera_path.hpp"
#include "eval/image_renderer.hpp"
#include "train/checkpoint.hpp"
#include "view/path_job.hpp"
#include "view/render_backend.hpp"

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

  data::CameraPathDefaults camera_defaults() override { return camera_defaults_; }
  RenderReply render(const RenderRequest& request) override;
  // The training cameras, a forward-facing capture's spiral, an orbit fitted to the cameras, and where the page
  // starts: a forward-facing capture from its first training camera, others from the orbit.
  StartCameras start_cameras() override { return start_cameras_; }
  ViewerStatus status() override;
  RenderProgress render_progress() override;

  // A recorded path renders into RUN/view_paths/path_<UTC time>/ (view/path_job.hpp); meanwhile the free camera's
  // renders answer "busy" with the path's progress.
  PathReply start_path(const PathRequest& request) override { return path_job_.start(request); }
  PathStatus path_status() override { return path_job_.status(); }
  void cancel_path() override { path_job_.cancel(); }

  int64_t step() const;
  // Image renderers built so far (the first at warm-up): one per checkpoint rendered, and one more after each path
  // render (which frees it for its own).
  size_t renderers_built() const { return renderers_built_; }

 private:
  void reload_if_newer();                              // with device_mutex_ held
  eval::ImageRenderer& renderer_for(const Camera& camera);  // with device_mutex_ held
  PathModel model_for_path();                          // with device_mutex_ held
  RenderReply render_on_device(const RenderRequest& request, const Camera& camera);  // with device_mutex_ held

  ocl::Context* ctx_;
  ViewRendererOptions options_;
  mutable std::mutex device_mutex_;  // the model, the renderer and the device's queue
  std::unique_ptr<train::TrainedModel> model_;
  // The image renderer of model_'s networks, reused by every request while model_ stays; reset when model_ changes
  // (it points into its networks) and when a path render needs the device's memory.
  std::unique_ptr<eval::ImageRenderer> renderer_;
  std::atomic<size_t> renderers_built_{0};
  mutable std::mutex info_mutex_;  // what status() reports, so it never waits for a render
  std::string checkpoint_;
  int64_t step_ = 0;
  StartCameras start_cameras_;
  data::CameraPathDefaults camera_defaults_;  // what the page's camera may leave out (eval::camera_path_defaults)
  size_t chunk_rays_ = 0;
  double warm_up_seconds_ = 0.0;
  std::atomic<uint64_t> newest_generation_{0};
  // The render under way or the last one (render_progress): written by the rendering thread, read by any.
  std::atomic<bool> progress_rendering_{false};
  std::atomic<uint64_t> progress_generation_{0};
  std::atomic<int> progress_divisor_{0};
  std::atomic<size_t> progress_done_{0}, progress_total_{0};
  std::atomic<int64_t> progress_started_ns_{0}, progress_ended_ns_{0};  // steady_clock
  std::atomic<size_t> waiting_{0};
  // Last: destroyed first, so a path under way is cancelled and joined while the model and the mutex still exist.
  PathJob path_job_;
};

}  // namespace mipnerf::view
