// "Render or score a checkpoint's views into a folder": the job `render` and `eval` run (and the preset benchmark's
// render). The job owns what both share — the backend choice for rendering, the renderer and its warm-up, the
// frames' progress, rank 0 writing the files under mpirun, and the records (render.json; metrics.json and
// metrics.md) — so the CLI only parses flags and prints the outcome.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "cl/context.hpp"
#include "data/dataset.hpp"
#include "eval/evaluate.hpp"
#include "eval/image_output.hpp"
#include "eval/view_cameras.hpp"
#include "train/checkpoint.hpp"

namespace mipnerf::eval {

// What every job shares.
struct RenderJob {
  const train::TrainedModel* model = nullptr;
  std::string checkpoint;    // the .mnck file (absolute), for the records
  size_t chunk_rays = 0;     // 0: the model's render_chunk_rays, lowered to what fits the device
  uint32_t supersample = 1;  // rays per pixel
  uint64_t seed = 0;         // of the supersampling jitter
  // Rays rendered so far over the whole job (of `total` = pixels × supersample of every frame), and what is being
  // rendered ("frame 3/120", "image 2/8").
  std::function<void(size_t done, size_t total, const std::string& detail)> progress;
};

// A render's frames as one video too: an H.264 MP4 (io/video), encoded on rank 0 as the frames arrive.
struct VideoOutput {
  std::string path;  // empty: no video
  double fps = 30.0;
  int crf = 18;  // libx264's constant rate factor, 0..51 (18: visually lossless)
  bool enabled() const { return !path.empty(); }
};

// Throws a one-line mipnerf::Error when `video` cannot be made of `frames`: no FFmpeg in this build, bad settings,
// a path whose folder cannot be written, frames of differing sizes, or an odd width or height. render_frames checks
// this on every rank before it renders anything; a caller may check earlier.
void check_video_output(const VideoOutput& video, const ViewFrames& frames);

struct RenderedFrames {
  size_t chunk_rays = 0;
  double warm_up_seconds = 0.0;
  double seconds = 0.0;            // every frame, warm-up excluded
  double megapixels = 0.0;         // every frame
  std::vector<std::string> files;  // rank 0: the first file written per frame (in `out`), its stem when none is
  std::string video;               // rank 0: the video written (absolute path); empty without one
};

// Renders every frame of `frames` and writes, on rank 0, OUT/<stem>.png/.exr per frame (none for formats "none"),
// the video when `video` asks for one, OUT/transforms.json (the cameras) and OUT/render.json (the record, with the
// video's path and settings).
RenderedFrames render_frames(ocl::Context& ctx, const RenderJob& job, const ViewFrames& frames, const std::string& out,
                             const OutputFormats& formats, const VideoOutput& video = {});

struct ScoreOptions {
  size_t views = 0;         // the split's first views (0: all; every scale of each)
  bool images = true;       // write the rendered, ground-truth and error images
  bool exr = false;         // ... and the EXR beside each render
  double error_gain = 4.0;  // error images: mean |render − truth| × this, clamped to 1
};

// Renders and scores the split's views (PSNR, SSIM, s/MP, per scale) and writes, on rank 0, OUT/metrics.json,
// OUT/metrics.md and (ScoreOptions::images) OUT/images/. `data_path` is recorded.
SplitScores score_split(ocl::Context& ctx, const RenderJob& job, const data::Split& split, const std::string& data_path,
                        const std::string& out, const ScoreOptions& options);

}  // namespace mipnerf::eval
