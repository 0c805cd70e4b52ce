// Internal to host/data: what a dataset file lists, before any image is read. The parsers of each format
// (formats/transforms_parse.cpp, formats/multiscale_blender_parse.cpp, formats/llff_capture.cpp) produce these; the loader (dataset.cpp) and the multiscale writer read
// the images they name.
#pragma once

#include <string>
#include <vector>

#include "data/dataset.hpp"
#include "data/intrinsics.hpp"
#include "data/pose.hpp"

namespace mipnerf::data::detail {

struct FrameSpec {
  std::string image_path;  // resolved, existing PNG
  std::string where;       // "DIR/transforms_train.json: frames[3]", for messages
  Matrix34 camera_to_world{};
  IntrinsicsSpec intrinsics;
  double near = 2.0, far = 6.0;
  double lossmult = 1.0;
  uint32_t scale_level = 0;
  uint32_t stored_factor = 1;  // the image is already downsampled by this (LLFF images_<factor>/); the load applies the rest
};

struct SplitSpec {
  std::string name;
  std::string source;   // the JSON file
  bool uniform_size = true;  // every image must have the first one's size (Blender: one camera_angle_x)
  std::vector<FrameSpec> frames;
};

// Blender: DIR/transforms_<split>.json for each requested (or present) split.
std::vector<SplitSpec> parse_blender(const std::string& dir, const LoadOptions& options);
// Single-file transforms.json, split into train/test by options.holdout_every; "val" holds the test views too.
std::vector<SplitSpec> parse_transforms_json(const std::string& file, const LoadOptions& options);
// Official multiscale metadata.json.
std::vector<SplitSpec> parse_multiscale_metadata(const std::string& file, const LoadOptions& options);
// The splits of a format that holds out views itself (transforms.json, LLFF): train, then the held-out views as
// "val" (what `train` scores at its end) and as "test"; those options.splits asks for (all when empty) and not empty.
std::vector<SplitSpec> with_held_out_splits(SplitSpec train, SplitSpec test, const LoadOptions& options);
// LLFF: DIR/poses_bounds.npy and its images (data/formats/llff_capture.hpp); "val" holds the held-out views, as "test".
std::vector<SplitSpec> parse_llff(const std::string& dir, const LoadOptions& options);

// The PNG a frame's file_path names, relative to `base_dir`: as given, or with ".png" appended (Blender
// writes file_path without extension). Throws naming the frame when it is missing or not a PNG.
std::string resolve_image_path(const std::string& base_dir, const std::string& file_path, const std::string& where);

// The split names to read: options.splits, or `available` in train, val, test order.
std::vector<std::string> wanted_splits(const LoadOptions& options);

// A transforms file gives near and far (globally, or on its first frame).
bool has_near_far(const io::Json& root);

// A transforms.json's frames in LLFF's NDC world (LoadOptions::forward_facing_ndc): moved by move_into_ndc_world from
// the file's nearest depth, with near/far the NDC range (options.near/far, else 0 and 1); and the file's depth range
// in the new units, as the spiral path takes it. Throws naming the file when it gives no near/far.
struct NdcFrames {
  std::vector<FrameSpec> frames;
  double scale = 1.0;                      // new units per file unit
  double near_depth = 0.0, far_depth = 0.0;  // the file's nearest near and farthest far, scaled
};
NdcFrames ndc_frames(const io::Json& root, const std::string& file, const LoadOptions& options);

// The near/far for a frame: the option if set, else the file's value, else Blender's 2 and 6.
void apply_near_far(FrameSpec& frame, const io::Json& global, const io::Json& object, const LoadOptions& options);

// `dir`/`name` (just `name` when dir is empty).
std::string join_path(const std::string& dir, const std::string& name);

}  // namespace mipnerf::data::detail

namespace mipnerf::data::detail {

// Tracks the first image's size of a split and throws when a later one differs (Blender splits share one
// camera_angle_x, so every image must have one size).
class SizeCheck {
 public:
  void check(uint32_t width, uint32_t height, const std::string& file);

 private:
  uint32_t width_ = 0, height_ = 0;
  std::string first_file_;
};

}  // namespace mipnerf::data::detail
