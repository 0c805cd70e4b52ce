// What `mipnerf-cl view` shows of a run folder, read afresh on every request so it follows a run while `train`
// writes it: its configuration, its logs as numbers, its checkpoints and its images.
#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>

namespace mipnerf::view {

// A CSV log (train_log.csv, val_log.csv) as {"columns": [...], "rows": [[numbers]...]}: at most `max_rows` rows,
// every k-th kept and always the last, so a long run's curve stays small; a cell that is not a number becomes null
// and a row cut short (being written) is left out. null when the file is missing.
nlohmann::json read_csv_log(const std::string& path, size_t max_rows = 2000);

// {"name", "config" (config.json, or null), "train_log", "val_log" (read_csv_log), "checkpoints" ([steps]),
//  "images": [{"folder", "name", "render", "gt", "error"}]} for every PNG render found in the run's val/ folder and in
// eval folders' images/ (a render X.png beside X_gt.png and X_error.png; paths relative to the run folder, "" when
// absent).
nlohmann::json run_state(const std::string& run_folder);

}  // namespace mipnerf::view
