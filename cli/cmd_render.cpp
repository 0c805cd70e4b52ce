// `mipnerf-cl render`: images from a checkpoint — a dataset split's cameras, an orbit, or a camera path file —
// at any resolution (intrinsics scaled, so cone radii follow the pixel size), as PNG and/or OpenEXR, and/or as one
// H.264 MP4 video (--video).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "core/error.hpp"
#include "core/suggest.hpp"
#include "parallel/world.hpp"
#include "common.hpp"
#include "data/paths/camera_path.hpp"
#include "eval/evaluate.hpp"
#include "eval/image_output.hpp"
#include "eval/render_job.hpp"
#include "eval/render_setup.hpp"
#include "eval/report.hpp"
#include "eval/view_cameras.hpp"
#include "io/path_hint.hpp"
#include "io/video.hpp"
#include "progress.hpp"
#include "render_estimate.hpp"
#include "train/checkpoint.hpp"

namespace mipnerf::cli {
namespace fs = std::filesystem;
namespace {

struct RenderArgs {
  std::string checkpoint;
  std::string data;
  std::string split;
  std::string path;  // "orbit" or a camera path file
  std::string out;
  std::string format = "png";
  // video
  std::string video;
  double fps = 30.0;
  int crf = 18;
  size_t views = 0;
  int scales = 0;
  // resolution
  double scale = 0.0;
  std::string size;
  uint32_t width = 0, height = 0;
  // orbit
  double radius = 0.0;
  double elevation = 30.0;
  double azimuth = 0.0;
  uint32_t frames = 120;
  double fov = 0.0;
  double focal = 0.0;
  // all cameras
  double near = 0.0, far = 0.0;
  uint32_t supersample = 1;
  uint64_t seed = 0;
  size_t chunk = 0;
};

bool given(const CLI::App& cmd, const char* flag) { return cmd.count(flag) > 0; }

// 30 → "30", 29.97 → "29.97".
std::string format_number(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", v);
  return text;
}

// The flag's value when it was given.
std::optional<double> if_given(const CLI::App& cmd, const char* flag, double value) {
  return given(cmd, flag) ? std::optional<double>(value) : std::nullopt;
}

data::ResolutionRequest resolution_of(const RenderArgs& args, const CLI::App& cmd) {
  data::ResolutionRequest request;
  request.scale = args.scale;
  if (given(cmd, "--scale") && !(args.scale > 0.0)) {
    throw Error("--scale " + std::to_string(args.scale) + ": the scale factor must be positive");
  }
  if (given(cmd, "--size")) {
    if (given(cmd, "--width") || given(cmd, "--height")) throw Error("give --size or --width/--height, not both");
    const auto [w, h] = data::parse_size(args.size, "--size");
    request.width = w;
    request.height = h;
  } else {
    if (given(cmd, "--width") && args.width == 0) throw Error("--width must be at least 1 pixel");
    if (given(cmd, "--height") && args.height == 0) throw Error("--height must be at least 1 pixel");
    request.width = args.width;
    request.height = args.height;
  }
  if (request.scale > 0.0 && (request.width || request.height)) {
    throw Error("give --scale or a size (--size, --width, --height), not both");
  }
  data::validate(request);
  return request;
}

// --video, --fps, --crf and --format none, before anything is opened (the frames' sizes are checked once they are
// known, by render_frames).
void check_video_arguments(const RenderArgs& args, const CLI::App& cmd, const eval::OutputFormats& formats) {
  if (!given(cmd, "--video")) {
    for (const char* flag : {"--fps", "--crf"}) {
      if (given(cmd, flag)) throw Error(std::string(flag) + " applies to --video only");
    }
    if (formats.none()) throw Error("--format none writes no images: give --video FILE.mp4 as well");
    return;
  }
  io::check_video_path(args.video);
  io::check_video_settings(args.video, args.fps, args.crf);
}

// What --path takes, for its help and its errors.
constexpr const char* kPathKinds =
    "orbit, spiral (an LLFF capture's official spiral) or a camera path file (a transforms-style JSON of frames, as a "
    "render's OUT/transforms.json)";

// The error for a --path that is neither a path kind nor a file: the kind or file meant, when one is close.
std::string unknown_path_kind(const std::string& path) {
  const std::string takes = " (--path takes orbit, spiral or a camera path file; a split's cameras: --split)";
  const std::string kind_hint = did_you_mean(path, {"orbit", "spiral"});
  if (!kind_hint.empty()) return "--path '" + path + "': " + kind_hint + takes;
  for (const char* split : {"train", "val", "test"}) {
    if (path == split) {
      return "--path '" + path + "': a dataset split's cameras are rendered with --split " + path +
             " (--path takes orbit, spiral or a camera path file)";
    }
  }
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    const std::string inside = (fs::path(path) / "transforms.json").string();
    return path + ": a folder, not a camera path file" +
           (fs::is_regular_file(inside, ec) ? "; did you mean '" + inside + "'?" : takes);
  }
  const std::string file_hint = io::missing_path_hint(path);
  return path + ": no such camera path file" + (file_hint.empty() ? takes : "; " + file_hint);
}

// The checks that need no device, so bad input fails before anything is opened.
void check_arguments(const RenderArgs& args, const CLI::App& cmd) {
  if (given(cmd, "--path") && given(cmd, "--split")) {
    throw Error("give --split (a dataset's cameras) or --path (orbit or a camera path file), not both");
  }
  const bool orbit = args.path == "orbit", spiral = args.path == "spiral";
  for (const char* flag : {"--radius", "--elevation", "--azimuth", "--fov", "--focal"}) {
    if (given(cmd, flag) && !orbit) throw Error(std::string(flag) + " applies to --path orbit only");
  }
  if (given(cmd, "--frames") && args.path.empty()) {
    throw Error("--frames applies to --path (orbit, spiral, or a camera path file whose frames are keyframes)");
  }
  if (given(cmd, "--fov") && given(cmd, "--focal")) throw Error("give --fov or --focal, not both");
  if (given(cmd, "--fov") && !(args.fov > 0.0 && args.fov < 180.0)) {
    throw Error("--fov " + std::to_string(args.fov) + ": the horizontal field of view must lie in (0, 180) degrees");
  }
  if (given(cmd, "--focal") && !(args.focal > 0.0 && std::isfinite(args.focal))) {
    throw Error("--focal must be a positive length in pixels");
  }
  if (given(cmd, "--radius") && !(args.radius > 0.0 && std::isfinite(args.radius))) {
    throw Error("--radius must be a positive distance in scene units");
  }
  if (given(cmd, "--frames") && args.frames == 0) throw Error("--frames must be at least 1");
  if (given(cmd, "--near") && !(args.near >= 0.0)) throw Error("--near must be >= 0");
  if (given(cmd, "--far") && !(args.far > 0.0)) throw Error("--far must be positive");
  if (given(cmd, "--near") && given(cmd, "--far") && !(args.far > args.near)) throw Error("--far must exceed --near");
  for (const char* flag : {"--views", "--scales"}) {
    if (given(cmd, flag) && given(cmd, "--path")) throw Error(std::string(flag) + " applies to --split only");
  }
  check_view_options(cmd, args.views, args.scales, args.supersample);
  if (!args.path.empty() && !orbit && !spiral) {
    std::error_code ec;
    if (!fs::is_regular_file(args.path, ec)) throw Error(unknown_path_kind(args.path));
  }
  const eval::OutputFormats formats = eval::parse_output_formats(args.format);
  resolution_of(args, cmd);
  check_video_arguments(args, cmd, formats);
}

// The frames --split, --path orbit or --path FILE asks for, at the requested resolution.
eval::ViewFrames frames_of(const RenderArgs& args, const CLI::App& cmd, const train::TrainedModel& model,
                           const std::string& checkpoint, const data::ResolutionRequest& resolution) {
  if (args.path == "orbit") {
    eval::OrbitRequest orbit;
    orbit.data = args.data;
    orbit.radius = if_given(cmd, "--radius", args.radius);
    orbit.elevation_deg = args.elevation;
    orbit.start_azimuth_deg = args.azimuth;
    orbit.frames = args.frames;
    orbit.fov_deg = if_given(cmd, "--fov", args.fov);
    orbit.focal_px = if_given(cmd, "--focal", args.focal);
    return eval::orbit_views(model, orbit, resolution);
  }
  if (args.path == "spiral") return eval::spiral_views(model, checkpoint, args.data, args.frames, resolution);
  if (!args.path.empty()) {  // with --frames, the file's frames are keyframes of a smooth path of that many frames
    return eval::path_views(model, args.path, resolution, given(cmd, "--frames") ? args.frames : 0);
  }
  eval::SplitViewRequest split;
  split.data = args.data;
  split.split = args.split.empty() ? "test" : args.split;
  split.views = args.views;
  split.scales = args.scales;
  return eval::split_views(model, checkpoint, split, resolution);
}

void run_render(const RenderArgs& args, const CLI::App& cmd) {
  check_arguments(args, cmd);
  const data::ResolutionRequest resolution = resolution_of(args, cmd);
  const eval::OutputFormats formats = eval::parse_output_formats(args.format);
  const std::string found = train::find_checkpoint(args.checkpoint);
  const std::string checkpoint = fs::absolute(found).lexically_normal().string();  // for the records

  auto ctx = open_context();
  const train::TrainedModel model = train::load_trained_model(*ctx, checkpoint);
  eval::ViewFrames frames = frames_of(args, cmd, model, checkpoint, resolution);
  eval::apply_depth_range(frames.cameras, if_given(cmd, "--near", args.near), if_given(cmd, "--far", args.far));
  const std::string run_folder = eval::run_folder_of(found);
  const std::string out = args.out.empty() ? (fs::path(run_folder) / frames.default_folder).string() : args.out;
  const bool root = parallel::world().is_root();
  if (root) make_output_folder(out, "--out");  // before the first frame, not after it
  Progress progress("render", 0);
  // Once the device is ready (the job's first report, after the warm-up): how much, and about how long.
  const std::optional<RecordedRate> rate =
      parallel::world().distributed() ? std::nullopt : recorded_rate(run_folder, ctx->device_info().name);
  RenderEstimate estimate(frames.cameras, args.supersample, rate, !args.path.empty());
  eval::RenderJob job;
  job.model = &model;
  job.checkpoint = checkpoint;
  job.chunk_rays = args.chunk;
  job.supersample = args.supersample;
  job.seed = args.seed;
  job.progress = [&, bar = progress.job_callback()](size_t done, size_t total, const std::string& detail) {
    if (const std::string line = estimate.report(done); !line.empty()) progress.note(line);
    bar(done, total, detail);
  };
  eval::VideoOutput video;
  video.path = args.video;
  video.fps = args.fps;
  video.crf = args.crf;
  const eval::RenderedFrames rendered = eval::render_frames(*ctx, job, frames, out, formats, video);
  progress.finish();
  if (!root) return;

  const double seconds = rendered.seconds, megapixels = rendered.megapixels;
  const std::string device = ctx->device_info().name;
  const auto& first = frames.cameras.front();
  const std::string ranks =
      parallel::world().distributed() ? " (" + std::to_string(parallel::world().size()) + " ranks, rank 0's)" : "";
  const std::string video_text =
      rendered.video.empty() ? "" : "; video in " + rendered.video + " (" + format_number(args.fps) + " fps)";
  std::printf("rendered %zu frames of %s (%ux%u%s) from step %lld in %.1f s, %.2f s/MP on %s%s; %s %s%s\n",
              frames.cameras.size(), frames.source.c_str(), first.width_px, first.height_px,
              args.supersample > 1 ? (", " + std::to_string(args.supersample) + " rays per pixel").c_str() : "",
              static_cast<long long>(model.step), seconds, megapixels > 0 ? seconds / megapixels : 0.0, device.c_str(),
              ranks.c_str(), formats.none() ? "records in" : "images in", out.c_str(), video_text.c_str());
}

}  // namespace

void register_render(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  auto* cmd = app.add_subcommand(
      "render", "Render images from a checkpoint: a dataset split, an orbit, or a camera path, at any resolution");
  cmd->add_option("--checkpoint", args->checkpoint, "A .mnck checkpoint, or a training --out folder (its newest)")
      ->required();
  cmd->add_option("--out", args->out, "Output folder (default: RUN/render_<split|orbit|path name>)");
  cmd->add_option("--format", args->format,
                  "png (8-bit sRGB), exr (linear RGB, depth Z, accumulation acc), both, or none (with --video)")
      ->capture_default_str();
  cmd->add_option("--video", args->video,
                  "Write the frames as one H.264 MP4 video too (a .mp4 file; --format none: alone)");
  cmd->add_option("--fps", args->fps, "Video: frames per second")->capture_default_str();
  cmd->add_option("--crf", args->crf, "Video: libx264's constant rate factor, 0..51 (lower: better, larger)")
      ->capture_default_str();
  // What to render.
  cmd->add_option("--split", args->split, "Render this split's cameras (train, val, test; default test)");
  cmd->add_option("--data", args->data, "Dataset of --split (default: the one the checkpoint was trained on)");
  cmd->add_option("--views", args->views, "Only the first N views of the split (all their scales)");
  cmd->add_option("--scales", args->scales, "Build the multiscale pyramid with N scales (default: as trained)");
  cmd->add_option("--path", args->path,
                  std::string(kPathKinds) +
                      "; a camera path's frames give transform_matrix and fl_x/fl_y/cx/cy/w/h or camera_angle_x. A "
                      "dataset split's cameras: --split");
  cmd->add_option("--radius", args->radius, "Orbit: distance from the target (default: the training cameras' mean)");
  cmd->add_option("--elevation", args->elevation, "Orbit: degrees above the horizontal plane")->capture_default_str();
  cmd->add_option("--azimuth", args->azimuth, "Orbit: azimuth of the first frame, degrees")->capture_default_str();
  cmd->add_option("--frames", args->frames,
                  "Orbit or spiral: number of frames; with a camera path file: interpolate its frames as keyframes to "
                  "this many (Catmull-Rom positions, slerped rotations)")
      ->capture_default_str();
  cmd->add_option("--fov", args->fov, "Orbit: horizontal field of view, degrees (default: the training camera's)");
  cmd->add_option("--focal", args->focal, "Orbit: focal length in pixels of the output size");
  // Resolution.
  cmd->add_option("--scale", args->scale, "Scale factor of the cameras' resolution (0.5: half the width and height)");
  cmd->add_option("--size", args->size, "Output size WIDTHxHEIGHT (intrinsics scaled to it)");
  cmd->add_option("--width", args->width, "Output width (height follows the aspect ratio unless given)");
  cmd->add_option("--height", args->height, "Output height (width follows the aspect ratio unless given)");
  // Rays.
  cmd->add_option("--supersample", args->supersample, "Jittered rays per pixel, averaged (1: one ray at the centre)")
      ->capture_default_str();
  cmd->add_option("--seed", args->seed, "Seed of the supersampling jitter")->capture_default_str();
  cmd->add_option("--near", args->near, "Near bound of every ray (default: the data's or the path's)");
  cmd->add_option("--far", args->far, "Far bound of every ray");
  cmd->add_option("--chunk", args->chunk, "Rays per chunk (default: render_chunk_rays, lowered to fit the device)");
  cmd->callback([args, cmd] { run_render(*args, *cmd); });
}

}  // namespace mipnerf::cli
