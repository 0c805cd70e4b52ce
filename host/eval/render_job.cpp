// Rendering and scoring a checkpoint's views into a folder.
#include "eval/render_job.hpp"

#include <cstdio>
#include <filesystem>
#include <memory>

#include "core/error.hpp"
#include "data/paths/camera_path.hpp"
#include "eval/image_renderer.hpp"
#include "eval/render_setup.hpp"
#include "eval/report.hpp"
#include "io/atomic_file.hpp"
#include "io/png.hpp"
#include "io/video.hpp"
#include "parallel/world.hpp"
#include "train/config.hpp"

namespace mipnerf::eval {
namespace fs = std::filesystem;
namespace {

size_t rays_of(const std::vector<Camera>& cameras, uint32_t supersample) {
  size_t rays = 0;
  for (const auto& c : cameras) rays += static_cast<size_t>(c.width_px) * c.height_px * supersample;
  return rays;
}

std::string size_text(const Camera& c) { return std::to_string(c.width_px) + "x" + std::to_string(c.height_px); }

// render.json: the record as report.cpp writes it, with the formats named ("none" too) and the video, when there is
// one, after them.
void write_render_json(const std::string& out, const RenderRecord& record, const VideoOutput& video,
                       const std::string& video_file, const std::vector<Camera>& cameras) {
  const nlohmann::ordered_json base = render_json(record);
  nlohmann::ordered_json j;
  for (const auto& [key, value] : base.items()) {
    j[key] = key == "formats" ? nlohmann::ordered_json(output_formats_name(record.formats)) : value;
    if (key == "formats" && !video_file.empty()) {
      const Camera& first = cameras.front();  // a video has frames, all of this size (check_video_output)
      j["video"] = {{"file", video_file},
                    {"format", "MP4, H.264 (libx264), yuv420p"},
                    {"width", first.width_px},
                    {"height", first.height_px},
                    {"frames", record.frames},
                    {"fps", video.fps},
                    {"crf", video.crf}};
    }
  }
  io::write_bytes_atomically((fs::path(out) / "render.json").string(), j.dump(2) + "\n");
}

}  // namespace

void check_video_output(const VideoOutput& video, const ViewFrames& frames) {
  io::check_video_path(video.path);
  io::check_video_settings(video.path, video.fps, video.crf);
  if (frames.cameras.empty()) throw Error(video.path + ": there are no frames to make a video of");
  const Camera& first = frames.cameras.front();
  for (size_t i = 1; i < frames.cameras.size(); ++i) {
    const Camera& c = frames.cameras[i];
    if (c.width_px != first.width_px || c.height_px != first.height_px) {
      throw Error(video.path + ": frame " + std::to_string(i + 1) + " is " + size_text(c) + " but frame 1 is " +
                  size_text(first) + ": a video's frames share one size; render one scale, or give --size WxH");
    }
  }
  io::check_video_frame_size(video.path, first.width_px, first.height_px);
}

RenderedFrames render_frames(ocl::Context& ctx, const RenderJob& job, const ViewFrames& frames, const std::string& out,
                             const OutputFormats& formats, const VideoOutput& video) {
  if (video.enabled()) check_video_output(video, frames);  // on every rank, before anything is rendered
  const train::TrainedModel& model = *job.model;
  RenderedFrames result;
  result.chunk_rays = render_chunk_rays(model, ctx.device_info(), job.chunk_rays);
  ImageRenderer renderer(ctx, model.spec, model.network_pointers(), model.grid_pointers(), frames.cameras,
                         RenderSettings{result.chunk_rays, job.supersample, job.seed});
  result.warm_up_seconds = renderer.warm_up();
  const size_t total = rays_of(frames.cameras, job.supersample);
  if (job.progress) job.progress(0, total, "");  // the rate (and ETA) counts from here, not from the first chunk
  const std::map<std::string, std::string> attributes = {{"mipnerf:checkpoint", job.checkpoint},
                                                         {"mipnerf:step", std::to_string(model.step)}};
  const bool root = parallel::world().is_root();  // under mpirun every rank holds each image; rank 0 writes it
  std::unique_ptr<io::VideoWriter> writer;  // rank 0 encodes; opened before the first frame, so a failure costs none
  if (root && video.enabled()) {
    const Camera& first = frames.cameras.front();
    writer = std::make_unique<io::VideoWriter>(video.path, first.width_px, first.height_px, video.fps, video.crf);
  }
  size_t before = 0;
  for (size_t i = 0; i < frames.cameras.size(); ++i) {
    const std::string detail = "frame " + std::to_string(i + 1) + "/" + std::to_string(frames.cameras.size());
    const RenderedImage image = renderer.render(i, [&](size_t done, size_t) {
      if (job.progress) job.progress(before + done, total, detail);
    });
    before += static_cast<size_t>(image.width) * image.height * job.supersample;
    result.seconds += image.seconds;
    result.megapixels += image.megapixels();
    if (!root) continue;
    const auto written = write_rendered_image((fs::path(out) / frames.stems[i]).string(), image, formats, attributes);
    result.files.push_back(written.empty() ? frames.stems[i] : fs::path(written.front()).filename().string());
    if (writer) writer->add_frame(image.rgb.data());
  }
  if (!root) return result;
  if (writer) {
    writer->finish();
    result.video = fs::absolute(video.path).lexically_normal().string();
  }
  data::write_camera_path((fs::path(out) / "transforms.json").string(), frames.cameras, result.files);
  RenderRecord record;
  record.checkpoint = job.checkpoint;
  record.step = model.step;
  record.source = frames.details;
  record.date = utc_timestamp();
  record.device = device_record(ctx.device_info());
  record.frames = frames.cameras.size();
  record.formats = formats;
  record.rays_per_pixel = job.supersample;
  record.chunk_rays = result.chunk_rays;
  record.warm_up_seconds = result.warm_up_seconds;
  record.render_seconds = result.seconds;
  record.megapixels = result.megapixels;
  write_render_json(out, record, video, result.video, frames.cameras);
  return result;
}

SplitScores score_split(ocl::Context& ctx, const RenderJob& job, const data::Split& split, const std::string& data_path,
                        const std::string& out, const ScoreOptions& options) {
  const train::TrainedModel& model = *job.model;
  const size_t chunk = render_chunk_rays(model, ctx.device_info(), job.chunk_rays);
  ImageRenderer renderer(ctx, model.spec, model.network_pointers(), model.grid_pointers(), split.cameras,
                         RenderSettings{chunk, job.supersample, job.seed});
  const double warm_up = renderer.warm_up();
  const std::vector<size_t> views = select_views(split, options.views);
  std::vector<Camera> scored;
  for (size_t i : views) scored.push_back(split.cameras[i]);
  const size_t total = rays_of(scored, job.supersample);
  if (job.progress) job.progress(0, total, "");
  const std::vector<std::string> stems = split_image_stems(split);
  const fs::path images = fs::path(out) / "images";
  EvaluateOptions evaluate;
  evaluate.max_views = options.views;
  size_t images_done = 0;
  evaluate.ray_progress = [&](size_t done, size_t) {
    if (!job.progress) return;
    job.progress(
        done, total,
        "image " + std::to_string(std::min(images_done + 1, views.size())) + "/" + std::to_string(views.size()));
  };
  evaluate.progress = [&](size_t done, size_t) { images_done = done; };
  if (options.images && parallel::world().is_root()) {  // under mpirun, rank 0 writes
    evaluate.on_image = [&](const ImageScore& score, const RenderedImage& image, const float* truth) {
      const std::string stem = (images / stems[score.index]).string();
      write_rendered_image(stem, image, {true, options.exr});
      io::write_png(stem + "_gt.png", image.width, image.height, 3, truth);
      const auto error =
          error_image(image.rgb.data(), truth, static_cast<size_t>(image.width) * image.height, options.error_gain);
      io::write_png(stem + "_error.png", image.width, image.height, 3, error.data());
    };
  }
  const SplitScores scores = evaluate_split(renderer, split, evaluate);
  if (!parallel::world().is_root()) return scores;  // every rank scored the gathered images alike; rank 0 records

  EvalRecord record;
  record.checkpoint = job.checkpoint;
  record.step = model.step;
  record.train_seconds = model.train_seconds;
  record.trained_on = model.trained_on;
  record.data = fs::absolute(data_path).lexically_normal().string();
  record.split = split.name;
  record.date = utc_timestamp();
  record.device = device_record(ctx.device_info());
  record.model = {{"variant", enum_name(model.config.variant)},
                  {"parameters", parameter_count(model)},
                  {"config", train::config_json(model.config)}};
  record.supersample = job.supersample;
  record.chunk_rays = chunk;
  record.warm_up_seconds = warm_up;
  record.image_folder = options.images ? "images" : "";
  record.image_stems = stems;
  auto metrics = metrics_json(scores, record);
  if (options.images) {
    char gain[32];
    std::snprintf(gain, sizeof(gain), "%g", options.error_gain);
    metrics["error_images"] = std::string("mean |render - ground truth| over RGB, times ") + gain + ", clamped to 1";
  }
  io::write_bytes_atomically((fs::path(out) / "metrics.json").string(), metrics.dump(2) + "\n");
  io::write_bytes_atomically((fs::path(out) / "metrics.md").string(), metrics_markdown(scores, record));
  return scores;
}

}  // namespace mipnerf::eval
