// The viewer's background job: a path recorded in the page, rendered into RUN/view_paths/path_<UTC time>/
// (frame_NNNN.png, transforms.json, render.json and, in a build with video, path.mp4) on a thread of its own, one at
// a time, holding the device frame after frame; cancellable between chunks of rays. The free camera's renders
// (view/view_renderer) answer "busy" while it runs.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

#include "cl/context.hpp"
#include "eval/render_job.hpp"
#include "eval/view_cameras.hpp"
#include "train/checkpoint.hpp"
#include "view/render_backend.hpp"

namespace mipnerf::view {

// The model a path renders and where it came from: read with the device mutex held, which the viewer holds whenever
// it swaps its model for a newer checkpoint's, so the model stays put for the whole path.
struct PathModel {
  const train::TrainedModel* model = nullptr;
  std::string checkpoint;
  size_t chunk_rays = 0;
};

class PathJob {
 public:
  // `device_mutex` is the viewer's: held by a path render from its first frame to its last. `model` is called with
  // it held (the viewer may free what it keeps on the device for its own renders there).
  PathJob(ocl::Context& ctx, std::mutex& device_mutex, std::function<PathModel()> model, std::string run_folder,
          uint64_t max_pixels);
  // Cancels a path under way and waits for its thread.
  ~PathJob();
  PathJob(const PathJob&) = delete;
  PathJob& operator=(const PathJob&) = delete;

  // Checks the request (frame sizes, the video's) and starts its thread; "busy" while another path renders or
  // starts, "bad_request" with the reason for a request it cannot render.
  PathReply start(const PathRequest& request);
  PathStatus status() const;
  void cancel() { cancel_ = true; }
  // From a start's claim until its thread's last step.
  bool running() const { return running_; }

 private:
  void render(eval::ViewFrames frames, std::string folder, eval::VideoOutput video);  // the path thread

  ocl::Context* ctx_;
  std::mutex* device_mutex_;
  std::function<PathModel()> model_;
  std::string run_folder_;
  uint64_t max_pixels_;
  std::mutex start_mutex_;  // held by start from its check to storing thread_
  std::thread thread_;
  std::atomic<bool> running_{false};
  std::atomic<bool> cancel_{false};
  mutable std::mutex status_mutex_;  // status_
  PathStatus status_;
};

}  // namespace mipnerf::view
