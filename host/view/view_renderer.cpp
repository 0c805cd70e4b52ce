// The viewer's renders: a run's newest checkpoint, the page's cameras, newest request first.
#include "view/view_renderer.hpp"

#include <chrono>
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

nlohmann::json frame_json(const Camera& c) {
  return {{"transform_matrix", data::pose_to_json(c.camera_to_world)},
          {"fl_x", c.focal_x_px},
          {"fl_y", c.focal_y_px},
          {"cx", c.center_x_px},
          {"cy", c.center_y_px},
          {"w", c.width_px},
          {"h", c.height_px}};
}

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
std::string start_cameras(const train::TrainedModel& model) {
  nlohmann::json out;
  out["train"] = nlohmann::json::array();
  const std::vector<Camera> train = eval::training_cameras(model, "");
  for (const Camera& c : train) out["train"].push_back(frame_json(c));
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
  eval::prepare_for_rendering(ctx);
  chunk_rays_ = eval::render_chunk_rays(*model_, ctx.device_info(), options_.chunk_rays);
  eval::OrbitRequest one;
  one.frames = 1;
  data::ResolutionRequest eighth;
  eighth.scale = 0.125;
  const eval::ViewFrames start = eval::orbit_views(*model_, one, eighth);
  eval::ImageRenderer renderer(ctx, model_->spec, model_->network_pointers(), start.cameras,
                               eval::RenderSettings{chunk_rays_, 1, 0});
  warm_up_seconds_ = renderer.warm_up();
  cameras_json_ = start_cameras(*model_);
  step_ = model_->step;
}

ViewRenderer::~ViewRenderer() = default;

int64_t ViewRenderer::step() const {
  std::lock_guard<std::mutex> lock(info_mutex_);
  return step_;
}

void ViewRenderer::reload_if_newer() {
  std::unique_ptr<train::TrainedModel> newer;
  const std::string path = load_newest(*ctx_, options_.run_folder, model_->step, newer);
  if (!newer) return;
  model_ = std::move(newer);
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
  if (waiting_.fetch_add(1) >= options_.max_waiting) {
    waiting_.fetch_sub(1);
    return answer(RenderReply::Status::busy);
  }
  std::unique_lock<std::mutex> lock(device_mutex_);
  waiting_.fetch_sub(1);
  if (superseded()) return answer(RenderReply::Status::superseded);
  try {
    reload_if_newer();
    const auto cameras = data::parse_camera_path(request.camera_json, "the page's camera",
                                                 eval::camera_path_defaults(*model_, {}));
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
    const eval::RenderedImage image = renderer.render(0, [&](size_t, size_t) {
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

std::string ViewRenderer::cameras_json() { return cameras_json_; }

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
