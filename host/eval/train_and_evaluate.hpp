// Train, then evaluate: a training run (train::Trainer) followed by rendering and scoring the scene's val views
// with the networks it trained, so a run ends with an image, a number, and what it cost. `mipnerf-cl train` and
// the preset benchmark both run through here.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>

#include "cl/context.hpp"
#include "eval/evaluate.hpp"
#include "eval/report.hpp"
#include "train/config.hpp"
#include "train/trainer.hpp"

namespace mipnerf::eval {

struct TrainAndEvaluateOptions {
  std::string data_path;  // the scene: its train split is trained on, its val split scored
  std::string out_dir;    // the run's folder: checkpoints, log, config.json (train::Trainer)
  bool resume = false;    // continue from the newest checkpoint in out_dir/checkpoints
  train::TrainHooks hooks;
  // > 0 (train --minutes): a new run's steps are sized to this wall-clock budget by a timed warm-up before
  // on_setup (train::Trainer::fit_steps_to_budget), which replaces config.steps; 0: config.steps as given.
  double budget_seconds = 0.0;
  // After the trainer is built (data loaded, memory planned, any resume applied), before the first step.
  std::function<void(train::Trainer&)> on_setup;
  // After training, interrupted or not, before the val evaluation; the trainer still holds its networks.
  std::function<void(train::Trainer&, const train::TrainResult&)> on_trained;

  // Score the val split after a run that was not interrupted. With config.val_every, the score of the last step is
  // that evaluation (same networks, same views; its images written then), and on_val_start and val_progress are
  // not called.
  bool evaluate_val = true;
  std::string val_image_folder;                     // where each val render goes as NNN_scaleK.png; empty: nowhere
  std::function<void(size_t images)> on_val_start;  // val loaded, renderer built, before image 1
  std::function<void(size_t done_images, size_t total)> val_progress;  // after every val image
  // The scores during training (config.val_every): before the first image, as rays render (over every image of the
  // score), and after the last with the seconds it took (kept out of the training time).
  std::function<void(int64_t step, size_t images)> on_periodic_val_start;
  std::function<void(size_t done_rays, size_t total_rays)> periodic_val_progress;
  std::function<void(double seconds)> on_periodic_val_end;
};

struct TrainAndEvaluateResult {
  TrainRecord record;  // for summary.json
  train::TrainResult train;
  std::optional<SplitScores> val;  // none when not asked for, interrupted, or failed (val_error)
  std::string val_error;           // why a val evaluation that was asked for failed (e.g. the data has no val split)
};

// Throws mipnerf::Error for what train::Trainer refuses (bad data, settings that do not fit, a mismatched resume)
// and for failed steps; a failing val evaluation is reported in val_error instead, the training being done.
TrainAndEvaluateResult train_and_evaluate(ocl::Context& ctx, const train::TrainConfig& config,
                                          const TrainAndEvaluateOptions& options);

}  // namespace mipnerf::eval
