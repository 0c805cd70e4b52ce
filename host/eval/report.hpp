// The records of a run: an evaluation's metrics.json (every score, per image, per scale and overall, with the
// metric definitions, the device, the checkpoint and the render time per megapixel) and a markdown table of the
// same; a training run's summary.json; a render's render.json.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "eval/evaluate.hpp"
#include "eval/image_output.hpp"
#include "io/json.hpp"
#include "train/trainer.hpp"

namespace mipnerf::eval {

// How the numbers were computed, written beside them.
extern const char* const kPsnrDefinition;
extern const char* const kSsimDefinition;

// What an evaluation records beside its scores.
struct EvalRecord {
  std::string checkpoint;                // the .mnck file
  int64_t step = 0;                      // its training step
  double train_seconds = 0.0;            // training time up to it
  std::string trained_on;                // the device that trained it
  std::string data;                      // the dataset evaluated
  std::string split;                     // "test", "val", ...
  std::string date;                      // ISO 8601, UTC
  io::Json device = io::Json::object();  // name, platform, vendor, driver version, ... (see device_record)
  io::Json model = io::Json::object();   // variant, parameter count, configuration
  uint32_t supersample = 1;
  size_t chunk_rays = 0;
  double warm_up_seconds = 0.0;          // the untimed first chunk (kernel builds, CLBlast compilation)
  std::string image_folder;              // where the images are, relative to metrics.json; empty when none were written
  std::vector<std::string> image_stems;  // by split index (split_image_stems), when images were written
};

// metrics.json's content, keys in a reading order. SSIMs that were not computed (images smaller than the window)
// are null.
nlohmann::ordered_json metrics_json(const SplitScores& scores, const EvalRecord& record);

// The per-scale table alone: scale, resolution, images, PSNR, SSIM, render s/MP, then the overall means.
std::string scale_table_markdown(const SplitScores& scores);

// metrics.md: a heading, what was evaluated where, the per-scale table, the definitions, and a per-image table.
std::string metrics_markdown(const SplitScores& scores, const EvalRecord& record);

// The current UTC time as "2026-11-21T09:13:56Z".
std::string utc_timestamp();

// What summary.json records of a training run beside its result.
struct TrainRecord {
  std::string device;               // the device's name
  size_t parameters = 0;            // of all networks
  size_t chunk_rays = 0;            // rays per chunk, as planned
  size_t planned_device_bytes = 0;  // train::MemoryPlan::total()
};
TrainRecord train_record(const train::Trainer& trainer, const std::string& device);

// summary.json's content: device, steps, interrupted, train_seconds, skipped_steps, parameters, chunk_rays,
// planned_device_bytes, checkpoint and, when `val` is given, its views, mean PSNR/SSIM, render s/MP and scales.
nlohmann::ordered_json summary_json(const TrainRecord& record, const train::TrainResult& result,
                                    const SplitScores* val);
// Writes out_dir/summary.json (atomically); returns its path.
std::string write_summary(const std::string& out_dir, const TrainRecord& record, const train::TrainResult& result,
                          const SplitScores* val);
// out_dir/summary.json.
std::string summary_path(const std::string& out_dir);
// out_dir/summary.json as written by write_summary; none when it is absent or does not read as JSON (its readers,
// a resume's "already finished" and render's time estimate, then act as if the run had none).
std::optional<io::Json> read_summary(const std::string& out_dir);

// What render.json records of a render.
struct RenderRecord {
  std::string checkpoint;                                            // the .mnck file (absolute)
  int64_t step = 0;                                                  // its training step
  nlohmann::ordered_json source = nlohmann::ordered_json::object();  // ViewFrames::details
  std::string date;                                                  // ISO 8601, UTC
  io::Json device = io::Json::object();                              // device_record
  size_t frames = 0;
  OutputFormats formats;
  uint32_t rays_per_pixel = 1;
  size_t chunk_rays = 0;
  double warm_up_seconds = 0.0;  // the untimed first chunk
  double render_seconds = 0.0;   // of every frame, warm-up excluded
  double megapixels = 0.0;       // of every frame
};
nlohmann::ordered_json render_json(const RenderRecord& record);
// Writes folder/render.json (atomically).
void write_render_record(const std::string& folder, const RenderRecord& record);

}  // namespace mipnerf::eval
