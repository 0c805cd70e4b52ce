// Parsers of the Blender format (transforms_<split>.json) and of the single-file transforms.json.
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>

#include "core/error.hpp"
#include "data/frames.hpp"
#include "data/image.hpp"
#include "data/path_policy.hpp"

namespace mipnerf::data::detail {
namespace fs = std::filesystem;

namespace {

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  return text;
}

bool is_file(const fs::path& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

// The frames of one transforms file (Blender or single-file): pose, file, intrinsics, near/far.
std::vector<FrameSpec> parse_frames(const io::Json& root, const std::string& file, const LoadOptions& options) {
  io::require_object(root, file);
  const IntrinsicsSpec global = read_intrinsics(root, {}, file);
  const auto& frames = io::require_array(root, "frames", file);
  if (frames.empty()) throw Error(file + ": 'frames' is empty: the split has no images");
  const std::string base_dir = fs::path(file).parent_path().string();
  std::vector<FrameSpec> specs;
  specs.reserve(frames.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    FrameSpec spec;
    spec.where = file + ": frames[" + std::to_string(i) + "]";
    io::require_object(frames[i], spec.where);
    // Everything the JSON says is checked before the file system is asked for the image.
    const std::string file_path = io::require_string(frames[i], "file_path", spec.where);
    spec.camera_to_world = pose_from_json(io::require_key(frames[i], "transform_matrix", spec.where), spec.where);
    spec.intrinsics = read_intrinsics(frames[i], global, spec.where);
    apply_near_far(spec, root, frames[i], options);
    spec.image_path = resolve_image_path(base_dir, file_path, spec.where);
    specs.push_back(std::move(spec));
  }
  return specs;
}

// options.world_around_cameras: every frame's pose (and near/far unless given in the options) in the world centred
// on where the cameras look, at RMS distance 1 (data::world_around_cameras).
void move_world_around_cameras(std::vector<FrameSpec>& frames, const std::string& file, const LoadOptions& options) {
  std::vector<Matrix34> poses;
  for (const auto& frame : frames) poses.push_back(frame.camera_to_world);
  const WorldAroundCameras world = world_around_cameras(poses, file);
  centre_and_scale(poses, world.centre, world.scale);
  for (size_t i = 0; i < frames.size(); ++i) {
    frames[i].camera_to_world = poses[i];
    if (!options.near) frames[i].near *= world.scale;
    if (!options.far) frames[i].far *= world.scale;
  }
  if (options.log) {
    char text[160];
    std::snprintf(text, sizeof(text), "centred on (%.3g, %.3g, %.3g) (%s) and scaled by %.4g", world.centre[0],
                  world.centre[1], world.centre[2],
                  world.centre_is_look_at ? "where the cameras look" : "the mean camera: their axes are parallel",
                  world.scale);
    options.log(LogLevel::info, file + ": the world for an unbounded run: " + text +
                                    ", so the cameras sit at RMS distance 1 from the centre");
  }
}

}  // namespace

bool has_near_far(const io::Json& root) {
  if (root.contains("near") && root.contains("far")) return true;
  const auto& frames = root.at("frames");
  return !frames.empty() && frames[0].is_object() && frames[0].contains("near") && frames[0].contains("far");
}

NdcFrames ndc_frames(const io::Json& root, const std::string& file, const LoadOptions& options) {
  if (!root.is_object() || !root.contains("frames") || !root.at("frames").is_array() || !has_near_far(root)) {
    io::require_object(root, file);
    io::require_array(root, "frames", file);
    throw Error(file + ": NDC rays (ray_shape = cylinder, for a forward-facing capture) need the capture's nearest "
                       "depth, and this file gives no near/far: add \"near\" and \"far\" (its scene units), or train "
                       "with --set ray_shape=cone");
  }
  LoadOptions from_file = options;  // the depths the file gives; options.near/far are NDC values here
  from_file.near.reset();
  from_file.far.reset();
  NdcFrames out;
  out.frames = parse_frames(root, file, from_file);
  double nearest = out.frames[0].near, farthest = out.frames[0].far;
  std::vector<Matrix34> poses;
  for (const auto& frame : out.frames) {
    nearest = std::min(nearest, frame.near);
    farthest = std::max(farthest, frame.far);
    poses.push_back(frame.camera_to_world);
  }
  out.scale = move_into_ndc_world(poses, nearest, file);
  out.near_depth = nearest * out.scale;
  out.far_depth = farthest * out.scale;
  const double near = options.near.value_or(0.0), far = options.far.value_or(1.0);
  if (!(near >= 0.0) || !(far > near)) {
    throw Error(file + ": near = " + std::to_string(near) + ", far = " + std::to_string(far) +
                " in NDC: need 0 <= near < far");
  }
  for (size_t i = 0; i < out.frames.size(); ++i) {
    out.frames[i].camera_to_world = poses[i];
    out.frames[i].near = near;
    out.frames[i].far = far;
  }
  return out;
}

std::string join_path(const std::string& dir, const std::string& name) {
  return dir.empty() ? name : (fs::path(dir) / name).string();
}

std::vector<std::string> wanted_splits(const LoadOptions& options) {
  if (!options.splits.empty()) return options.splits;
  return {"train", "val", "test"};
}

std::string resolve_image_path(const std::string& base_dir, const std::string& file_path, const std::string& where) {
  check_inside_folder(base_dir, file_path, where, "file_path");
  const fs::path given = fs::path(base_dir) / file_path;
  const fs::path with_png = fs::path(given.string() + ".png");
  const std::string extension = lower(given.extension().string());
  static const char* const kOtherImageTypes[] = {".exr", ".tif", ".tiff", ".bmp", ".webp", ".gif"};
  for (const char* other : kOtherImageTypes) {
    if (extension == other && !is_file(with_png)) {
      throw Error(given.lexically_normal().string() + ": only PNG and JPEG images are supported (" + where +
                  "); convert the images to PNG and update file_path");
    }
  }
  const bool png_or_jpeg = has_image_extension(given);
  if (is_file(given) && png_or_jpeg) return given.lexically_normal().string();
  if (is_file(with_png)) return with_png.lexically_normal().string();
  if (is_file(given)) return given.lexically_normal().string();  // a PNG without extension: decoding will tell
  const fs::path expected = png_or_jpeg ? given : with_png;
  throw Error(expected.lexically_normal().string() + ": no such file (listed by " + where + ")");
}

void apply_near_far(FrameSpec& frame, const io::Json& global, const io::Json& object, const LoadOptions& options) {
  auto pick = [&](const char* key, const std::optional<double>& override_value, double fallback) {
    if (override_value) return *override_value;
    if (auto v = io::optional_number(object, key, frame.where)) return *v;
    if (auto v = io::optional_number(global, key, frame.where)) return *v;
    return fallback;
  };
  frame.near = pick("near", options.near, 2.0);
  frame.far = pick("far", options.far, 6.0);
  if (!(frame.near >= 0.0) || !(frame.far > frame.near)) {
    throw Error(frame.where + ": near = " + std::to_string(frame.near) + ", far = " + std::to_string(frame.far) +
                ": need 0 <= near < far");
  }
}

std::vector<SplitSpec> parse_blender(const std::string& dir, const LoadOptions& options) {
  std::vector<std::string> present;
  for (const char* name : {"train", "val", "test"}) {
    if (is_file(join_path(dir, std::string("transforms_") + name + ".json"))) present.push_back(name);
  }
  std::string present_text;
  for (const auto& name : present) present_text += (present_text.empty() ? "" : ", ") + name;
  std::vector<SplitSpec> splits;
  for (const auto& name : wanted_splits(options)) {
    const std::string file = join_path(dir, "transforms_" + name + ".json");
    if (!is_file(file)) {
      if (options.splits.empty()) continue;  // optional when not asked for
      throw Error(file + ": no such file (this dataset has the splits: " +
                  (present_text.empty() ? std::string("none") : present_text) + ")");
    }
    SplitSpec split;
    split.name = name;
    split.source = file;
    split.uniform_size = true;
    split.frames = parse_frames(io::read_json(file), file, options);
    splits.push_back(std::move(split));
  }
  return splits;
}

std::vector<SplitSpec> parse_transforms_json(const std::string& file, const LoadOptions& options) {
  for (const auto& name : options.splits) {
    if (name != "train" && name != "test" && name != "val") {
      throw Error(file + ": a single transforms.json has only the splits train and test (every " +
                  std::to_string(options.holdout_every) + "th frame held out; val is the same views), not '" + name +
                  "'");
    }
  }
  if (options.holdout_every < 0) throw Error("holdout_every must be >= 0");
  if (options.world_around_cameras && options.forward_facing_ndc) {
    throw Error(file + ": an unbounded run casts world rays; NDC is for a forward-facing capture: not both");
  }
  const io::Json root = io::read_json(file);
  std::vector<FrameSpec> frames;
  if (options.forward_facing_ndc) {
    const NdcFrames ndc = ndc_frames(root, file, options);
    frames = ndc.frames;
    if (options.log) {
      char text[200];
      std::snprintf(text, sizeof(text),
                    "the NDC world of a forward-facing capture: scaled by %.4g so that its nearest depth, %.4g, "
                    "becomes 4/3, and recentred on the average camera",
                    ndc.scale, ndc.near_depth / ndc.scale);
      options.log(LogLevel::info, file + ": " + text);
    }
  } else {
    frames = parse_frames(root, file, options);
    if (!has_near_far(root) && !(options.near && options.far) && options.log) {
      options.log(LogLevel::warning, file + " gives no near/far: using near " + std::to_string(frames[0].near) +
                                         ", far " + std::to_string(frames[0].far) + " (set them with --near/--far)");
    }
  }
  if (options.world_around_cameras) move_world_around_cameras(frames, file, options);
  SplitSpec train, test;
  train.name = "train";
  test.name = "test";
  train.source = test.source = file;
  train.uniform_size = test.uniform_size = false;  // each frame may have its own w/h
  for (size_t i = 0; i < frames.size(); ++i) {
    const bool held_out = options.holdout_every > 0 && i % options.holdout_every == 0 && frames.size() > 1;
    (held_out ? test : train).frames.push_back(std::move(frames[i]));
  }
  return with_held_out_splits(std::move(train), std::move(test), options);
}

std::vector<SplitSpec> with_held_out_splits(SplitSpec train, SplitSpec test, const LoadOptions& options) {
  SplitSpec val = test;
  val.name = "val";
  std::vector<SplitSpec> splits;
  for (auto* split : {&train, &val, &test}) {
    const bool wanted = options.splits.empty() ||
                        std::find(options.splits.begin(), options.splits.end(), split->name) != options.splits.end();
    if (wanted && !split->frames.empty()) splits.push_back(std::move(*split));
  }
  return splits;
}

}  // namespace mipnerf::data::detail
