// The viewer's recorded paths, rendered in the background into the run folder.
#include "view/path_job.hpp"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <filesystem>

#include "core/error.hpp"
#include "data/paths/camera_path.hpp"
#include "io/video.hpp"

namespace mipnerf::view {
namespace fs = std::filesystem;
namespace {

// The nearest even frame size at or below the path's (its first frame's: a path's frames share one size), or an
// empty request when both sides are even already.
data::ResolutionRequest even_video_size(const eval::ViewFrames& frames) {
  data::ResolutionRequest even;
  if (frames.cameras.empty()) return even;
  const Camera& first = frames.cameras.front();
  if (first.width_px % 2 == 0 && first.height_px % 2 == 0) return even;
  even.width = std::max<uint32_t>(2, first.width_px - first.width_px % 2);
  even.height = std::max<uint32_t>(2, first.height_px - first.height_px % 2);
  return even;
}

struct PathCancelled {};  // thrown from a path render's progress callback when the page cancelled it

// A new folder for a path render, run-relative: view_paths/path_20261126T081500Z (…_2, _3 when taken).
std::string new_path_folder(const std::string& run_folder) {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &utc);
  const std::string base = std::string("view_paths/path_") + stamp;
  std::string folder = base;
  for (int n = 2; fs::exists(fs::path(run_folder) / folder); ++n) folder = base + "_" + std::to_string(n);
  return folder;
}

}  // namespace

PathJob::PathJob(ocl::Context& ctx, std::mutex& device_mutex, std::function<PathModel()> model, std::string run_folder,
                 uint64_t max_pixels)
    : ctx_(&ctx),
      device_mutex_(&device_mutex),
      model_(std::move(model)),
      run_folder_(std::move(run_folder)),
      max_pixels_(max_pixels) {}

PathJob::~PathJob() {
  cancel_ = true;
  std::lock_guard<std::mutex> starting(start_mutex_);  // no start is storing a thread meanwhile
  if (thread_.joinable()) thread_.join();
}

PathStatus PathJob::status() const {
  std::lock_guard<std::mutex> lock(status_mutex_);
  return status_;
}

PathReply PathJob::start(const PathRequest& request) {
  PathReply reply;
  // One start at a time, held until the new thread is in thread_: a second caller meanwhile is told "busy" at once.
  // Checking running_ and setting it after the device wait let two requests both move-assign a joinable thread_
  // (std::terminate: a double-click on "render the path"); and a claim by the flag alone let a path that ended at
  // once (cancelled) free it before its starter had stored the thread, so the next start joined or replaced a thread
  // still being assigned (ThreadSanitizer's report on the concurrency test).
  std::unique_lock<std::mutex> starting(start_mutex_, std::try_to_lock);
  if (!starting.owns_lock() || running_) {
    reply.status = PathReply::Status::busy;
    reply.message = "a path is rendering already: wait for it, or cancel it first";
    return reply;
  }
  // Set before anything that can fail, given back on every way out but the new thread's start (a bad request, or a
  // throw from the file system or std::thread), so no failure leaves the viewer "busy" for good; the free camera's
  // renders read it to answer "busy" meanwhile.
  running_ = true;
  struct Claim {
    std::atomic<bool>& running;
    bool kept = false;
    ~Claim() {
      if (!kept) running = false;
    }
  } claim{running_};
  cancel_ = false;  // a cancel from here on stops this path
  // The previous path's thread cleared the flag as its last step, so it has ended or is about to.
  if (thread_.joinable()) thread_.join();
  eval::ViewFrames frames;
  eval::VideoOutput video;
  const std::string folder = new_path_folder(run_folder_);
  try {
    data::ResolutionRequest size;
    if (request.divisor > 1) size.scale = 1.0 / request.divisor;
    frames = eval::path_views(request.keyframes, "the viewer's recorded path", size, request.frames);
    if (io::video_supported()) {
      // H.264 in 4:2:0 needs even sides, and the page's divisors are sizes for people, not exact ones: 1/8 of the
      // LLFF flower's 504x378 is 63x47. Such a path renders one pixel smaller per odd side (62x46), the field of
      // view kept with square pixels (data::resize_camera), instead of being refused.
      const data::ResolutionRequest even = even_video_size(frames);
      if (even.width != 0) frames = eval::path_views(request.keyframes, "the viewer's recorded path", even, request.frames);
    }
    for (const Camera& c : frames.cameras) {
      if (static_cast<uint64_t>(c.width_px) * c.height_px > max_pixels_) {
        throw Error("the path's frames are larger than the viewer renders");
      }
    }
    if (io::video_supported()) {
      video.path = (fs::path(run_folder_) / folder / "path.mp4").string();
      video.fps = request.fps;
      eval::check_video_output(video, frames);
    }
  } catch (const std::exception& e) {  // mipnerf::Error, or the file system's
    std::error_code ec;
    fs::remove(fs::path(run_folder_) / folder, ec);  // the video check's probe made it; only if empty
    reply.status = PathReply::Status::bad_request;
    reply.message = e.what();
    return reply;
  }
  {
    std::lock_guard<std::mutex> lock(status_mutex_);
    status_ = PathStatus{};
    status_.state = PathStatus::State::rendering;
    status_.frames = frames.cameras.size();
    status_.folder = folder;
  }
  thread_ = std::thread(
      [this, frames = std::move(frames), folder, video]() mutable { render(std::move(frames), folder, video); });
  claim.kept = true;  // the thread clears running_ when it ends
  return reply;
}

void PathJob::render(eval::ViewFrames frames, std::string folder, eval::VideoOutput video) {
  const auto started = std::chrono::steady_clock::now();
  auto seconds_since_start = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  };
  PathStatus::State state = PathStatus::State::done;
  std::string message;
  try {
    std::lock_guard<std::mutex> device(*device_mutex_);
    const PathModel model = model_();
    eval::RenderJob job;
    job.model = model.model;
    job.checkpoint = model.checkpoint;
    job.chunk_rays = model.chunk_rays;
    const size_t frame_count = frames.cameras.size();
    job.progress = [&](size_t done, size_t total, const std::string&) {
      if (cancel_) throw PathCancelled{};
      std::lock_guard<std::mutex> lock(status_mutex_);
      const double fraction = total == 0 ? 0.0 : static_cast<double>(done) / static_cast<double>(total);
      status_.frames_done = static_cast<size_t>(fraction * static_cast<double>(frame_count));
      status_.seconds = seconds_since_start();
      status_.eta_seconds = fraction > 0.0 ? status_.seconds * (1.0 - fraction) / fraction : 0.0;
    };
    const eval::RenderedFrames rendered = eval::render_frames(
        *ctx_, job, frames, (fs::path(run_folder_) / folder).string(), eval::parse_output_formats("png"), video);
    std::lock_guard<std::mutex> lock(status_mutex_);
    status_.frames_done = frame_count;
    status_.video = rendered.video.empty() ? "" : folder + "/" + fs::path(rendered.video).filename().string();
    status_.first_frame = folder + "/" + frames.stems.front() + ".png";
  } catch (const PathCancelled&) {
    ctx_->queue().finish();
    std::error_code ec;
    fs::remove(fs::path(run_folder_) / folder, ec);  // only when no frame was written yet (an empty folder)
    state = PathStatus::State::cancelled;
    message = "cancelled from the page; the frames rendered so far are kept, the video is not";
  } catch (const std::exception& e) {
    state = PathStatus::State::failed;
    message = e.what();
  }
  {
    std::lock_guard<std::mutex> lock(status_mutex_);
    status_.state = state;
    status_.message = message;
    status_.seconds = seconds_since_start();
    status_.eta_seconds = 0.0;
  }
  running_ = false;
}

}  // namespace mipnerf::view
