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

// Makes the context ready to render: CLBlast's tuned parameters loaded where CLBlast runs the networks' products.
// Rendering uses gemm_backend=auto's choice for this device (load_trained_model), not the checkpoint's setting: that
// one chose for the training device, and a model trained on a CPU with the host BLAS must still render on a GPU. On
// a device where the host BLAS runs them, nothing is loaded and no tune is suggested.
void prepare_for_rendering(ocl::Context& ctx);

struct RenderedFrames {
  size_t chunk_rays = 0;
  double warm_up_seconds = 0.0;
  double seconds = 0.0;            // every frame, warm-up excluded
  double megapixels = 0.0;         // every frame
  std::vector<std::string> files;  // rank 0: the first file written per frame (in `out`)
};

// Renders every frame of `frames` and writes, on rank 0, OUT/<stem>.png/.exr per frame, OUT/transforms.json (the
// cameras) and OUT/render.json (the record).
RenderedFrames render_frames(ocl::Context& ctx, const RenderJob& job, const ViewFrames& frames, const std::string& out,
                             const OutputFormats& formats);

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
