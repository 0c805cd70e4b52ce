// The record of an evaluation: metrics.json (every score, per image, per scale and overall, with the metric
// definitions, the device, the checkpoint and the render time per megapixel) and a markdown table of the same.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "eval/evaluate.hpp"
#include "io/json.hpp"

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

}  // namespace mipnerf::eval
