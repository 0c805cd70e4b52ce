// The viewer's renders: a run's newest checkpoint, the page's cameras, newest request first.
#include "view/view_renderer.hpp"

#include <algorithm>
#include <chrono>
#include <filesystem>

#include "core/error.hpp"
#include "data/paths/camera_path.hpp"
#include "data/intrinsics.hpp"
#include "data/pose.hpp"
#include "eval/image_renderer.hpp"
#include "eval/render_job.hpp"
#include "eval/render_setup.hpp"
#include "eval/view_cameras.hpp"
#include "io/png.hpp"

namespace mipnerf::view {
namespace fs = std::filesystem;
namespace {

struct Superseded {};  // thrown from the chunk callback when a newer request arrived

RenderReply answer(RenderReply::Status status, const std::string& message = "") {
  RenderReply reply;
  reply.status = status;
  reply.message = message;
  return reply;
}

// Depth or accumulation as grey levels: depth over [near, far] (near white), accumulation as is.
std::vector<float> grey_image(const eval::RenderedImage& image, RenderOutput output, const Camera& camera) {
  const size_t pixels = static_cast<size_t>(image.width) * image.height;
  std::vector<float> rgb(pixels * 3);
  for (size_t p = 0; p < pixels; ++p) {
    float v = image.acc[p];
    if (output == RenderOutput::depth) {
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
StartCameras start_cameras_of(const train::TrainedModel& model, const std::string& checkpoint) {
  StartCameras out;
  out.train = eval::training_cameras(model, "");
  // A forward-facing capture's official render path (the spiral `render --path spiral` follows), when the run's data
  // is an LLFF capture that still exists; the page starts from it and `spin` walks along it.
  try {
    out.spiral = eval::spiral_views(model, checkpoint, "", 120, {}).cameras;
  } catch (const Error&) {  // not an LLFF capture, or its data is gone: no spiral to offer
  }
  // Where the page starts: a forward-facing capture from its first training camera (an orbit would look at it from
  // behind its cameras, where it was never seen), cameras around the scene from the orbit fitted to them.
  std::vector<data::Matrix34> poses;
  for (const Camera& c : out.train) poses.push_back(c.camera_to_world);
  if (!out.train.empty() && data::looks_forward(poses)) {
    out.start = StartCameras::View::train;
    out.why = "a forward-facing capture: its first training camera (an orbit would look from behind it)";
  } else {
    out.start = StartCameras::View::orbit;
    out.why = out.train.empty() ? "the training data is gone: the default orbit"
                                : "cameras around the scene: the orbit fitted to them";
  }
  data::OrbitOptions orbit;
  if (!out.train.empty()) {
    orbit = data::orbit_around(out.train);
  } else {
    eval::OrbitRequest one;
    one.frames = 1;
    orbit.intrinsics = eval::orbit_views(model, one, {}).cameras.front();
  }
  orbit.frames = 1;
  out.orbit.target = orbit.target;
  out.orbit.up = orbit.up;
  out.orbit.radius = orbit.radius;
  out.orbit.elevation_deg = orbit.elevation_deg;
  out.orbit.frame = data::orbit_cameras(orbit).front();
  return out;
}

}  // namespace

ViewRenderer::ViewRenderer(ocl::Context& ctx, ViewRendererOptions options)
    : ctx_(&ctx),
      options_(std::move(options)),
      path_job_(ctx, device_mutex_, [this] { return model_for_path(); }, options_.run_folder, options_.max_pixels) {
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
  // The renderer warmed up here is the one the first requests render through.
  warm_up_seconds_ = renderer_for(eval::orbit_views(*model_, one, eighth).cameras.front()).warm_up();
  start_cameras_ = start_cameras_of(*model_, checkpoint_);
  camera_defaults_ = eval::camera_path_defaults(*model_, {});
  step_ = model_->step;
}

// The path job (the last member) is destroyed first: it cancels a path under way and waits for it.
ViewRenderer::~ViewRenderer() = default;

int64_t ViewRenderer::step() const {
  std::lock_guard<std::mutex> lock(info_mutex_);
  return step_;
}

void ViewRenderer::reload_if_newer() {
  std::unique_ptr<train::TrainedModel> newer;
  const std::string path = load_newest(*ctx_, options_.run_folder, model_->step, newer);
  if (!newer) return;
  renderer_.reset();  // it points into the old model's networks
  model_ = std::move(newer);
  // camera_defaults_ stay: a newer checkpoint of the run has the same data and settings.
  std::lock_guard<std::mutex> lock(info_mutex_);
  checkpoint_ = path;
  step_ = model_->step;
}

eval::ImageRenderer& ViewRenderer::renderer_for(const Camera& camera) {
  if (renderer_) {
    renderer_->set_cameras({camera});
  } else {
    renderer_ = std::make_unique<eval::ImageRenderer>(*ctx_, model_->spec, model_->network_pointers(),
                                                      model_->grid_pointers(), std::vector<Camera>{camera},
                                                      eval::RenderSettings{chunk_rays_, 1, 0});
    ++renderers_built_;
  }
  return *renderer_;
}

PathModel ViewRenderer::model_for_path() {
  renderer_.reset();  // the path builds its own renderer: the device's memory is its while it runs
  std::lock_guard<std::mutex> lock(info_mutex_);
  return PathModel{model_.get(), checkpoint_, chunk_rays_};
}

RenderReply ViewRenderer::render(const RenderRequest& request) {
  // The newest generation seen; an older request is answered at once.
  uint64_t newest = newest_generation_.load();
  while (request.generation > newest && !newest_generation_.compare_exchange_weak(newest, request.generation)) {
  }
  auto superseded = [&] { return newest_generation_.load() > request.generation; };
  if (superseded()) return answer(RenderReply::Status::superseded);
  if (path_job_.running()) {
    const PathStatus path = path_job_.status();
    const std::string what = path.state == PathStatus::State::rendering
                                 ? "rendering the recorded path (frame " + std::to_string(path.frames_done + 1) + "/" +
                                       std::to_string(path.frames) + ")"
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
    Camera camera = request.camera;
    if (request.divisor > 1) {
      data::ResolutionRequest smaller;
      smaller.scale = 1.0 / request.divisor;
      camera = data::resize_camera(camera, smaller);
    }
    if (static_cast<uint64_t>(camera.width_px) * camera.height_px > options_.max_pixels) {
      return answer(RenderReply::Status::bad_request, "the image is larger than the viewer renders");
    }
    return render_on_device(request, camera);
  } catch (const Superseded&) {
    ctx_->queue().finish();  // the chunks already enqueued end before the next render starts
    return answer(RenderReply::Status::superseded);
  } catch (const Error& e) {
    renderer_.reset();  // whatever failed, the next request starts from a fresh renderer
    return answer(RenderReply::Status::bad_request, e.what());
  }
}

RenderReply ViewRenderer::render_on_device(const RenderRequest& request, const Camera& camera) {
  eval::ImageRenderer& renderer = renderer_for(camera);
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
    if (newest_generation_.load() > request.generation) throw Superseded{};
  });
  const bool rgb = request.output == RenderOutput::rgb;
  const std::vector<float> grey = rgb ? std::vector<float>() : grey_image(image, request.output, camera);
  const auto bytes = io::quantize_8bit(rgb ? image.rgb.data() : grey.data(), static_cast<size_t>(image.width) * image.height * 3);
  const auto png = io::encode_png8(image.width, image.height, 3, bytes.data());
  RenderReply reply;
  reply.png.assign(png.begin(), png.end());
  reply.width = image.width;
  reply.height = image.height;
  reply.seconds = image.seconds;
  reply.step = model_->step;
  return reply;
}

RenderProgress ViewRenderer::render_progress() {
  // The render's seconds so far (or, when none is under way, the last one's, up to its end).
  RenderProgress p;
  p.rendering = progress_rendering_.load();
  const int64_t started = progress_started_ns_.load();
  const int64_t until = p.rendering ? std::chrono::steady_clock::now().time_since_epoch().count()
                                    : progress_ended_ns_.load();
  p.seconds = started == 0 ? 0.0 : static_cast<double>(std::max<int64_t>(0, until - started)) * 1e-9;
  p.generation = progress_generation_.load();
  p.divisor = progress_divisor_.load();
  p.done_rays = progress_done_.load();
  p.total_rays = progress_total_.load();
  return p;
}

ViewerStatus ViewRenderer::status() {
  std::lock_guard<std::mutex> lock(info_mutex_);
  ViewerStatus s;
  s.device = ctx_->device_info().name;
  s.step = step_;
  s.checkpoint = fs::path(checkpoint_).filename().string();
  s.chunk_rays = chunk_rays_;
  s.warm_up_seconds = warm_up_seconds_;
  return s;
}

}  // namespace mipnerf::view
