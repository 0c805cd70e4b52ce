// The CSV logs of a run folder: train_log.csv (a row every log_every steps, after a skipped step and at the last)
// and val_log.csv (config.val_every). Rank 0 writes them.
#pragma once

#include <cstdint>
#include <fstream>
#include <string>

namespace mipnerf::train {

// The columns of OUT/train_log.csv, its first line (with its newline).
inline constexpr const char* kTrainingLogHeader = "step,wall_seconds,loss,psnr,learning_rate,rays_per_second,skipped\n";

// The columns of out_dir/val_log.csv (config.val_every), its first line: train_seconds is the training clock at the
// score (val time excluded), val_seconds what the scoring itself took. Written here, read by eval/run_curves.
inline constexpr const char* kValLogColumns = "step,train_seconds,val_psnr,val_ssim,val_images,val_seconds";

// Opens a run's CSV log: appended to when resuming at `step` > 0 (its rows after `step`, and a row cut short by a
// kill, dropped first, atomically: each step appears once), else started anew with `header_line`. Throws naming
// the file when it cannot be written.
void open_log(std::ofstream& csv, const std::string& csv_path, int64_t step, const std::string& header_line);

// Rewrites the log keeping its rows up to `step` (and the header; `header_line` when it held nothing).
void trim_log(const std::string& csv_path, int64_t step, const std::string& header_line);

}  // namespace mipnerf::train
