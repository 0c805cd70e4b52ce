// The viewer's renders: a run's newest checkpoint, the page's cameras, newest request first.
#include "view/view_renderer.hpp"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "data/camera_path.hpp"
#include "data/intrinsics.hpp"
#include "data/pose.hpp"
#include "eval/image_renderer.hpp"
#include "eval/render_job.hpp"
#include "eval/render_setup.hpp"
#include "eval/view_cameras.hpp"
#include "io/png.hpp"
#include "io/video.hpp"

namespace mipnerf::view {
namespace fs = std::filesystem;
namespace {

struct Superseded {};  // thrown from the chunk callback when a newer request arrived
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

RenderReply answer(RenderReply::Status status, const std::string& message = "") {
  RenderReply reply;
  reply.status = status;
  reply.message = message;
  return reply;
}

// A camera as the page receives it: everything the camera path reader reads back (near/far and the lens included:
// a forward-facing run's cameras render between NDC's 0 and 1, not Blender's default 2..6).
nlohmann::json frame_json(const Camera& c) { return data::camera_frame_json(c); }

// Depth or accumulation as grey levels: depth over [near, far] (near white), accumulation as is.
std::vector<float> grey_image(const eval::RenderedImage& image, const std::string& output, const Camera& camera) {
  const size_t pixels = static_cast<size_t>(image.width) * image.height;
  std::vector<float> rgb(pixels * 3);
  for (size_t p = 0; p < pixels; ++p) {
    float v = image.acc[p];
    if (output == "depth") {
      const double span = camera.far - camera.near;
      v = static_cast<float>(1.0 - (image.depth[p] - camera.near) / (span > 0 ? span : 1.0));
    }
    rgb[3 * p] = rgb[3 * p + 1] = rgb[3 * p + 2] = v;
  }
  return rgb;
}

// The newest checkpoint of `folder` that loads (a checkpoint is written atomically, but one may be corrupt).
std::string load_newest(ocl::Context& ctx, const std::string& run_folder, int64_t newer_than,
                        std::unique_ptr<train::TrainedModel>& model) {
  const fs::path folder = fs::is_directory(fs::path(run_folder) / "checkpoints") ? fs::path(run_folder) / "checkpoints"
                                                                               : fs::path(run_folder);
  auto found = train::list_checkpoints(folder.string());
  for (auto it = found.rbegin(); it != found.rend() && it->first > newer_than; ++it) {
    try {
      model = std::make_unique<train::TrainedModel>(train::load_trained_model(ctx, it->second));
      return it->second;
    } catch (const Error&) {
      continue;  // a checkpoint that does not verify: try the one before it
    }
  }
  return {};
}

// Where the page's camera starts: the training cameras and an orbit fitted to them (Blender's default orbit when the
// training data is gone).
std::string start_cameras(const train::TrainedModel& model, const std::string& checkpoint) {
  nlohmann::json out;
  out["train"] = nlohmann::json::array();
  const std::vector<Camera> train = eval::training_cameras(model, "");
  for (const Camera& c : train) out["train"].push_back(frame_json(c));
  // A forward-facing capture's official render path (the spiral `render --path spiral` follows), when the run's data
  // is an LLFF capture that still exists; the page starts from it and `spin` walks along it.
  out["spiral"] = nlohmann::json::array();
  try {
    for (const Camera& c : eval::spiral_views(model, checkpoint, "", 120, {}).cameras) {
      out["spiral"].push_back(frame_json(c));
    }
  } catch (const Error&) {  // not an LLFF capture, or its data is gone: no spiral to offer
  }
  // Where the page starts: a forward-facing capture from its first training camera (an orbit would look at it from
  // behind its cameras, where it was never seen), cameras around the scene from the orbit fitted to them.
  std::vector<data::Matrix34> poses;
  for (const Camera& c : train) poses.push_back(c.camera_to_world);
  if (!train.empty() && data::looks_forward(poses)) {
    out["start"] = {{"view", "train"}, {"index", 0},
                    {"why", "a forward-facing capture: its first training camera (an orbit would look from behind it)"}};
  } else if (!train.empty()) {
    out["start"] = {{"view", "orbit"}, {"why", "cameras around the scene: the orbit fitted to them"}};
  } else {
    out["start"] = {{"view", "orbit"}, {"why", "the training data is gone: the default orbit"}};
  }
  data::OrbitOptions orbit;
  if (!train.empty()) {
    orbit = data::orbit_around(train);
  } else {
    eval::OrbitRequest one;
    one.frames = 1;
    orbit.intrinsics = eval::orbit_views(model, one, {}).cameras.front();
  }
  orbit.frames = 1;
  out["orbit"] = {{"target", orbit.target},
                  {"up", orbit.up},
                  {"radius", orbit.radius},
                  {"elevation_deg", orbit.elevation_deg},
                  {"frame", frame_json(data::orbit_cameras(orbit).front())}};
  return out.dump();
}

}  // namespace

ViewRenderer::ViewRenderer(ocl::Context& ctx, ViewRendererOptions options) : ctx_(&ctx), options_(std::move(options)) {
  checkpoint_ = load_newest(ctx, options_.run_folder, -1, model_);
  if (!model_) {
    throw Error(options_.run_folder + ": no checkpoint that loads (a run folder of `mipnerf-cl train`, with "
                "checkpoints/ckpt_*.mnck; while training, wait for the first checkpoint)");
  }
  chunk_rays_ = eval::render_chunk_rays(*model_, ctx.device_info(), options_.chunk_rays);
  eval::OrbitRequest one;
  one.frames = 1;
  data::ResolutionRequest eighth;
  eighth.scale = 0.125;
  const eval::ViewFrames start = eval::orbit_views(*model_, one, eighth);
  eval::ImageRenderer renderer(ctx, model_->spec, model_->network_pointers(), start.cameras,
                               eval::RenderSettings{chunk_rays_, 1, 0});
  warm_up_seconds_ = renderer.warm_up();
  cameras_json_ = start_cameras(*model_, checkpoint_);
  camera_defaults_ = eval::camera_path_defaults(*model_, {});
  step_ = model_->step;
}

ViewRenderer::~ViewRenderer() {
  path_cancel_ = true;
  std::lock_guard<std::mutex> starting(path_start_mutex_);  // no start is storing a thread meanwhile
  if (path_thread_.joinable()) path_thread_.join();
}

int64_t ViewRenderer::step() const {
  std::lock_guard<std::mutex> lock(info_mutex_);
  return step_;
}

void ViewRenderer::reload_if_newer() {
  std::unique_ptr<train::TrainedModel> newer;
  const std::string path = load_newest(*ctx_, options_.run_folder, model_->step, newer);
  if (!newer) return;
  model_ = std::move(newer);
  // camera_defaults_ stay: a newer checkpoint of the run has the same data and settings.
  std::lock_guard<std::mutex> lock(info_mutex_);
  checkpoint_ = path;
  step_ = model_->step;
}

RenderReply ViewRenderer::render(const RenderRequest& request) {
  RenderReply reply;
  // The newest generation seen; an older request is answered at once.
  uint64_t newest = newest_generation_.load();
  while (request.generation > newest && !newest_generation_.compare_exchange_weak(newest, request.generation)) {
  }
  auto superseded = [&] { return newest_generation_.load() > request.generation; };
  if (superseded()) return answer(RenderReply::Status::superseded);
  if (path_running_) {
    std::lock_guard<std::mutex> lock(path_mutex_);
    const std::string what = path_status_.state == "rendering"
                                 ? "rendering the recorded path (frame " + std::to_string(path_status_.frames_done + 1) +
                                       "/" + std::to_string(path_status_.frames) + ")"
                                 : "starting a recorded path";
    return answer(RenderReply::Status::busy,
                  "the device is " + what + "; the free camera renders again once it ends or is cancelled");
  }
  if (waiting_.fetch_add(1) >= options_.max_waiting) {
    waiting_.fetch_sub(1);
    return answer(RenderReply::Status::busy);
  }
  std::unique_lock<std::mutex> lock(device_mutex_);
  waiting_.fetch_sub(1);
  if (superseded()) return answer(RenderReply::Status::superseded);
  try {
    reload_if_newer();
    const auto cameras = data::parse_camera_path(request.camera_json, "the page's camera", camera_defaults_);
    if (cameras.size() != 1) return answer(RenderReply::Status::bad_request, "give exactly one frame");
    Camera camera = cameras.front();
    if (request.divisor > 1) {
      data::ResolutionRequest smaller;
      smaller.scale = 1.0 / request.divisor;
      camera = data::resize_camera(camera, smaller);
    }
    if (static_cast<uint64_t>(camera.width_px) * camera.height_px > options_.max_pixels) {
      return answer(RenderReply::Status::bad_request, "the image is larger than the viewer renders");
    }
    eval::ImageRenderer renderer(*ctx_, model_->spec, model_->network_pointers(), {camera},
                                 eval::RenderSettings{chunk_rays_, 1, 0});
    progress_generation_ = request.generation;
    progress_divisor_ = request.divisor;
    progress_done_ = 0;
    progress_total_ = static_cast<size_t>(camera.width_px) * camera.height_px;
    progress_started_ns_ = std::chrono::steady_clock::now().time_since_epoch().count();
    progress_rendering_ = true;
    struct Done {
      ViewRenderer& self;
      ~Done() {
        self.progress_ended_ns_ = std::chrono::steady_clock::now().time_since_epoch().count();
        self.progress_rendering_ = false;
      }
    } done_rendering{*this};
    const eval::RenderedImage image = renderer.render(0, [&](size_t done, size_t total) {
      progress_done_ = done;
      progress_total_ = total;
      if (superseded()) throw Superseded{};
    });
    const std::vector<float> grey = request.output == "rgb" ? std::vector<float>() : grey_image(image, request.output, camera);
    const float* samples = request.output == "rgb" ? image.rgb.data() : grey.data();
    const auto bytes = io::quantize_8bit(samples, static_cast<size_t>(image.width) * image.height * 3);
    const auto png = io::encode_png8(image.width, image.height, 3, bytes.data());
    reply.png.assign(png.begin(), png.end());
    reply.width = image.width;
    reply.height = image.height;
    reply.seconds = image.seconds;
    reply.step = model_->step;
    return reply;
  } catch (const Superseded&) {
    ctx_->queue().finish();  // the chunks already enqueued end before the next render starts
    return answer(RenderReply::Status::superseded);
  } catch (const Error& e) {
    return answer(RenderReply::Status::bad_request, e.what());
  }
}

PathReply ViewRenderer::start_path(const PathRequest& request) {
  PathReply reply;
  // One start at a time, held until the new thread is in path_thread_: a second caller meanwhile is told "busy" at
  // once. Checking path_running_ and setting it after the device wait let two requests both move-assign a joinable
  // path_thread_ (std::terminate: a double-click on "render the path"); and a claim by the flag alone let a path that
  // ended at once (cancelled) free it before its starter had stored the thread, so the next start joined or replaced
  // a thread still being assigned (ThreadSanitizer's report on the concurrency test).
  std::unique_lock<std::mutex> starting(path_start_mutex_, std::try_to_lock);
  if (!starting.owns_lock() || path_running_) {
    reply.status = PathReply::Status::busy;
    reply.message = "a path is rendering already: wait for it, or cancel it first";
    return reply;
  }
  // Set before anything that can fail, given back on every way out but the new thread's start (a bad request, or a
  // throw from the file system or std::thread), so no failure leaves the viewer "busy" for good; render() reads it to
  // answer "busy" meanwhile.
  path_running_ = true;
  struct Claim {
    std::atomic<bool>& running;
    bool kept = false;
    ~Claim() {
      if (!kept) running = false;
    }
  } claim{path_running_};
  path_cancel_ = false;  // a cancel from here on stops this path
  // The previous path's thread cleared the flag as its last step, so it has ended or is about to.
  if (path_thread_.joinable()) path_thread_.join();
  eval::ViewFrames frames;
  eval::VideoOutput video;
  const std::string folder = new_path_folder(options_.run_folder);
  try {
    std::lock_guard<std::mutex> lock(device_mutex_);
    data::ResolutionRequest size;
    if (request.divisor > 1) size.scale = 1.0 / request.divisor;
    frames = eval::path_views(*model_, nlohmann::json::parse(request.keyframes_json), "the viewer's recorded path",
                              size, request.frames);
    for (const Camera& c : frames.cameras) {
      if (static_cast<uint64_t>(c.width_px) * c.height_px > options_.max_pixels) {
        throw Error("the path's frames are larger than the viewer renders");
      }
    }
    if (io::video_supported()) {
      video.path = (fs::path(options_.run_folder) / folder / "path.mp4").string();
      video.fps = request.fps;
      eval::check_video_output(video, frames);
    }
  } catch (const std::exception& e) {  // mipnerf::Error, or the keyframes' JSON
    std::error_code ec;
    fs::remove(fs::path(options_.run_folder) / folder, ec);  // the video check's probe made it; only if empty
    reply.status = PathReply::Status::bad_request;
    reply.message = e.what();
    return reply;
  }
  {
    std::lock_guard<std::mutex> lock(path_mutex_);
    path_status_ = PathStatus{};
    path_status_.state = "rendering";
    path_status_.frames = frames.cameras.size();
    path_status_.folder = folder;
  }
  path_thread_ = std::thread([this, frames = std::move(frames), folder, video]() mutable {
    render_path(std::move(frames), folder, video);
  });
  claim.kept = true;  // the thread clears path_running_ when it ends
  return reply;
}

void ViewRenderer::render_path(eval::ViewFrames frames, std::string folder, eval::VideoOutput video) {
  const auto started = std::chrono::steady_clock::now();
  auto seconds_since_start = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  };
  std::string state = "done", message;
  try {
    std::lock_guard<std::mutex> device(device_mutex_);
    eval::RenderJob job;
    job.model = model_.get();
    {
      std::lock_guard<std::mutex> info(info_mutex_);
      job.checkpoint = checkpoint_;
    }
    job.chunk_rays = chunk_rays_;
    const size_t frame_count = frames.cameras.size();
    job.progress = [&](size_t done, size_t total, const std::string&) {
      if (path_cancel_) throw PathCancelled{};
      std::lock_guard<std::mutex> lock(path_mutex_);
      const double fraction = total == 0 ? 0.0 : static_cast<double>(done) / static_cast<double>(total);
      path_status_.frames_done = static_cast<size_t>(fraction * static_cast<double>(frame_count));
      path_status_.seconds = seconds_since_start();
      path_status_.eta_seconds = fraction > 0.0 ? path_status_.seconds * (1.0 - fraction) / fraction : 0.0;
    };
    const eval::RenderedFrames rendered = eval::render_frames(
        *ctx_, job, frames, (fs::path(options_.run_folder) / folder).string(), eval::parse_output_formats("png"), video);
    std::lock_guard<std::mutex> lock(path_mutex_);
    path_status_.frames_done = frame_count;
    path_status_.video = rendered.video.empty() ? "" : folder + "/" + fs::path(rendered.video).filename().string();
    path_status_.first_frame = folder + "/" + frames.stems.front() + ".png";
  } catch (const PathCancelled&) {
    ctx_->queue().finish();
    std::error_code ec;
    fs::remove(fs::path(options_.run_folder) / folder, ec);  // only when no frame was written yet (an empty folder)
    state = "cancelled";
    message = "cancelled from the page; the frames rendered so far are kept, the video is not";
  } catch (const std::exception& e) {
    state = "failed";
    message = e.what();
  }
  {
    std::lock_guard<std::mutex> lock(path_mutex_);
    path_status_.state = state;
    path_status_.message = message;
    path_status_.seconds = seconds_since_start();
    path_status_.eta_seconds = 0.0;
  }
  path_running_ = false;
}

std::string ViewRenderer::path_status_json() {
  std::lock_guard<std::mutex> lock(path_mutex_);
  const PathStatus& p = path_status_;
  return nlohmann::json{{"state", p.state},       {"frames_done", p.frames_done}, {"frames", p.frames},
                        {"seconds", p.seconds},   {"eta_seconds", p.eta_seconds}, {"folder", p.folder},
                        {"video", p.video},       {"first_frame", p.first_frame}, {"message", p.message}}
      .dump();
}

void ViewRenderer::cancel_path() { path_cancel_ = true; }

std::string ViewRenderer::cameras_json() { return cameras_json_; }

std::string ViewRenderer::render_progress_json() {
  // The render's seconds so far (or, when none is under way, the last one's, up to its end).
  const bool rendering = progress_rendering_.load();
  const int64_t started = progress_started_ns_.load();
  const int64_t until = rendering ? std::chrono::steady_clock::now().time_since_epoch().count() : progress_ended_ns_.load();
  const double seconds = started == 0 ? 0.0 : static_cast<double>(std::max<int64_t>(0, until - started)) * 1e-9;
  return nlohmann::json{{"rendering", rendering},
                        {"generation", progress_generation_.load()},
                        {"divisor", progress_divisor_.load()},
                        {"done_rays", progress_done_.load()},
                        {"total_rays", progress_total_.load()},
                        {"seconds", seconds}}
      .dump();
}

std::string ViewRenderer::status_json() {
  std::lock_guard<std::mutex> lock(info_mutex_);
  return nlohmann::json{{"device", ctx_->device_info().name},
                        {"step", step_},
                        {"checkpoint", fs::path(checkpoint_).filename().string()},
                        {"chunk_rays", chunk_rays_},
                        {"warm_up_seconds", warm_up_seconds_}}
      .dump();
}

}  // namespace mipnerf::view
