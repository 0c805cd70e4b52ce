// Datasets on the host: each split's cameras and composited pixels, all images (and scales) together, loaded from
// any format of the table in data/formats (Blender, multiscale Blender, transforms.json, LLFF).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/log.hpp"
#include "core/camera.hpp"
#include "data/image.hpp"

namespace mipnerf::data {

// The formats; each has its row in data/formats (detection, parsing, traits, effects, render path).
enum class DatasetFormat {
  blender,             // DIR/transforms_<split>.json, frames with file_path + transform_matrix, camera_angle_x
  multiscale_blender,  // DIR/metadata.json as written by mip-NeRF's convert_blender_data.py (or make-multiscale)
  transforms_json,     // one transforms.json with every frame; intrinsics fl_x, fl_y, cx, cy, w, h
  llff,                // DIR/poses_bounds.npy + DIR/images[_<factor>]/ (forward-facing captures; data/formats/llff_capture.hpp)
  count                // not a format: the number of them (data/formats checks every one has its row)
};
const char* format_name(DatasetFormat format);

// Options only LLFF captures read.
struct LlffOptions {
  bool spherify = false;  // re-pose a 360° capture around its centre (world rays, cones)
  bool ndc = true;        // not spherified: near 0, far 1 in NDC (cylinder rays); false: world depths from bounds
};

struct LoadOptions {
  Background background = Background::white;  // composite RGBA onto it (the paper: white for Blender)
  // 1: the images as stored. n > 1: build the multiscale pyramid on the fly, as the paper's multiscale
  // Blender: every image also box-downsampled ×2, ×4, … ×2^(n−1) (n = 4 in the paper), each with
  // lossmult = its pixel area in full-resolution pixels (1, 4, 16, 64) and focal length / 2^j.
  int scales = 1;
  // Box-downsample every stored image by this power of two first (the official Config.factor: lego at
  // 400×400 with factor 4 trains at 100×100). Intrinsics follow; lossmult does not change (it is relative
  // to the resolution trained at). Applied before the multiscale pyramid, which then starts from it.
  uint32_t factor = 1;
  std::optional<double> near, far;  // override the files' values (default: the file's, else 2 and 6)
  std::vector<std::string> splits;  // splits to load ("train", "val", "test"); empty = every split present
  // transforms.json and LLFF (the formats that hold out views themselves): every n-th frame (0, n, 2n …) becomes
  // "test" (and "val"), the rest "train"; 0 = none.
  int holdout_every = 8;
  LlffOptions llff;  // LLFF captures only
  // transforms.json only: move the world into the frame an unbounded run's contraction expects (data::
  // world_around_cameras: the origin where the cameras look, their RMS distance 1; LLFF's spherify does the same),
  // from every frame of the file whatever the splits, so train, eval and render see one world. Near/far from the file
  // (or the defaults) scale with it; near/far given here are in the new units.
  bool world_around_cameras = false;
  // transforms.json only: NDC rays (cylinders) for a forward-facing capture, as LLFF's (llff.ndc): every frame moves
  // into LLFF's NDC world (positions scaled so the file's nearest depth becomes 1/0.75, then recentred on the average
  // camera: data::ndc_world_of) and gets near 0, far 1 (near/far given here are NDC values, as for LLFF). The file must
  // give near/far; the loaded cameras must share one projection (focal length and principal point per image width
  // and height), since NDC is the frustum of one camera.
  bool forward_facing_ndc = false;
  LogFn log;         // notes and warnings (defaults taken, splits skipped)
};

// One split: images of possibly different sizes (scales), each with its own camera, pixels packed together.
struct Split {
  std::string name;                    // "train", "val", "test"
  std::string source;                  // the file that listed its frames
  std::vector<Camera> cameras;         // [C]
  std::vector<uint32_t> scale_levels;  // [C]: j of the image (downsampled by 2^j); 0 = full resolution
  std::vector<std::string> files;      // [C]: the PNG each image came from
  std::vector<uint64_t> pixel_offsets{0};  // [C + 1]: image c's pixels are [offsets[c], offsets[c + 1])
  std::vector<float> rgb;              // [pixels][3], composited, row-major per image (pixel y·width + x)

  size_t num_images() const { return cameras.size(); }
  uint64_t num_pixels() const { return pixel_offsets.back(); }
  const float* image_rgb(size_t c) const { return rgb.data() + 3 * pixel_offsets[c]; }
  int num_scales() const;  // 1 + the largest scale level
};

struct Dataset {
  std::string path;
  DatasetFormat format = DatasetFormat::blender;
  Background background = Background::white;
  std::vector<Split> splits;  // in the order train, val, test (those present)

  bool has_split(const std::string& name) const;
  // Throws mipnerf::Error listing the splits there are.
  const Split& split(const std::string& name) const;
  std::string split_names() const;  // "train, val"
};

// Finds the format of `path` (a folder, or a transforms.json / metadata.json file) and loads it. Every
// problem is a one-line mipnerf::Error naming the file and what is wrong: missing files, malformed JSON,
// missing keys, images of differing size, non-finite or non-rigid poses, unreadable PNGs, distortion.
Dataset load_dataset(const std::string& path, const LoadOptions& options = {});

// Appends one image (straight RGBA) and its full-resolution camera to `split`, with `scales` pyramid levels
// built by downsample2 (cameras scaled by scale_camera), each composited onto `background`.
void append_image(Split& split, const RgbaImage& image, const Camera& camera, uint32_t base_level, int scales,
                  Background background, const std::string& file);

// The camera of the same view downsampled by `factor` (a power of two): focal lengths and principal point
// / factor (pixel coordinates shrink with the pixels), size / factor, lossmult · factor² (the pixel's area in
// full-resolution pixels). The cone radius follows from the smaller focal length through the ray kernel.
Camera scale_camera(const Camera& camera, uint32_t factor);

// The camera a stored image of `camera` trains at with `factor` (the loader's rule): cropped at its right and bottom
// edges to the largest size the factor divides (the intrinsics stay exact: pixel k still covers source pixels
// [f·k, f·k + f)), then scale_camera. Throws when the image is smaller than the factor.
Camera camera_at_factor(const Camera& camera, uint32_t factor);

}  // namespace mipnerf::data
