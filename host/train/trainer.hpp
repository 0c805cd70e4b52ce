// Training end to end: dataset → device, networks and Adam, the host graph step by step, non-finite
// steps skipped, a CSV log, atomic checkpoints, resume, and a clean stop on request (Ctrl-C).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "cl/context.hpp"
#include "data/dataset.hpp"
#include "graph/graph_spec.hpp"
#include "mlp/adam.hpp"
#include "mlp/grid_table.hpp"
#include "mlp/network.hpp"
#include "ops/loss.hpp"
#include "train/config.hpp"
#include "train/memory_plan.hpp"
#include "train/run_log.hpp"
#include "train/step_budget.hpp"
#include "train/train_step.hpp"

namespace mipnerf::train {

// What one step did, for progress displays.
struct StepReport {
  int64_t step = 0;  // 1-based number of this step
  int64_t total_steps = 0;
  double loss = 0.0;  // the official weighted total (λ·coarse + fine)
  double psnr = 0.0;  // per-channel PSNR of the last level on this batch
  double learning_rate = 0.0;
  double rays_per_second = 0.0;  // over the steps since the previous report
  double train_seconds = 0.0;    // of this run plus those before a resume
  bool skipped = false;          // non-finite loss or gradients: no update was applied
};

class Trainer;


// A val score taken during training (config.val_every): one row of out_dir/val_log.csv.
struct ValScore {
  double psnr = 0.0;  // mean over the scored views (and scales)
  double ssim = 0.0;
  size_t images = 0;  // how many images were scored
};

struct TrainHooks {
  std::function<void(const StepReport&)> on_step;  // after every step
  std::function<bool()> should_stop;               // checked after every step: true → checkpoint and return
  // Every config.val_every steps and after the last: scores the trainer's networks on val views. Its wall time is
  // logged beside the score and kept out of the training seconds (StepReport, TrainResult, checkpoints).
  std::function<ValScore(Trainer&)> score_val;
  // Tests: called after the backward of every step, before the gradients are checked (e.g. to inject a NaN).
  AfterBackward after_backward;
};

struct TrainResult {
  int64_t last_step = 0;       // the step the final checkpoint holds
  bool interrupted = false;    // stopped by should_stop before the configured steps
  int64_t skipped_steps = 0;   // non-finite steps of this run
  double train_seconds = 0.0;  // total, including before a resume
  double seconds_this_run = 0.0;
  std::string checkpoint;   // path of the final checkpoint
  double final_psnr = 0.0;  // last step's batch PSNR
};

class Trainer {
 public:
  // Loads the training split of `data_path` and prepares the networks; with `resume`, continues from the
  // newest checkpoint in out_dir/checkpoints (its configuration must match `config`, execution settings
  // aside). Throws mipnerf::Error for bad data, settings that do not fit the device, or a mismatched resume.
  Trainer(ocl::Context& ctx, const TrainConfig& config, const std::string& data_path, const std::string& out_dir,
          bool resume);
  ~Trainer();

  TrainResult run(const TrainHooks& hooks = {});

  const TrainConfig& config() const { return config_; }
  const graph::GraphSpec& spec() const { return spec_; }
  const MemoryPlan& memory() const { return memory_; }
  const data::Dataset& dataset() const { return dataset_; }
  std::vector<std::unique_ptr<mlp::Network>>& networks() { return networks_; }
  const std::vector<std::unique_ptr<mlp::Network>>& networks() const { return networks_; }
  const std::vector<std::unique_ptr<mlp::Adam>>& optimisers() const { return optimisers_; }  // one per network
  std::vector<mlp::Network*> network_pointers() const;  // as the graph and the renderer take them
  std::vector<mlp::GridTable*> grid_pointers() const;   // Zip-NeRF's grids (none for mip-NeRF)
  int64_t step() const { return step_; }
  size_t parameter_count() const;

  // train --minutes: before the first step of a new run, times a warm-up (train/step_budget.hpp: a cold step, then
  // warm steps), puts the networks and Adam back to their initial state, and sets config().steps to the steps that
  // fit in what the warm-up left of `budget_seconds`, so the run (its learning-rate schedule too) is bit for bit the
  // run of `steps = config().steps`. The warm-up's time counts as training time (train_seconds). Records the choice
  // in config().time_budget, OUT/config.json and OUT/time_budget.json. Throws mipnerf::Error for a budget that is
  // not positive, one too short for a single step after the warm-up, and a run already past step 0 (a resumed run
  // keeps the steps it recorded).
  StepBudget fit_steps_to_budget(double budget_seconds);

  // Writes out_dir/checkpoints/ckpt_<step>.mnck (atomically, train/checkpoint.hpp) and prunes old ones; returns
  // its path.
  std::string save_checkpoint();

 private:
  struct Impl;
  struct RunTiming;
  // run()'s pieces: the step and the periodic actions around it.
  StepParts step_parts();
  StepOutcome profiled_step(StepParts& parts, int64_t step, const TrainHooks& hooks);
  void note_skipped_step(int64_t step, int consecutive_bad, TrainResult& result);  // throws after max_bad_steps
  StepReport report_of(const StepOutcome& outcome, RunTiming& timing) const;
  void log_step(const StepReport& report, RunTiming& timing);
  void score_val_if_due(const TrainHooks& hooks, RunTiming& timing);
  std::string checkpoint_now(const RunTiming& timing);
  void restore(const std::string& path);
  // Rank 0's housekeeping of out_dir before the first step: stale temporaries removed, and the checkpoint a
  // --resume continues from ("" = step 0), or in `refusal` why this folder cannot be trained into.
  std::string choose_start(bool resume, std::string& refusal);
  std::string checkpoint_folder() const;  // out_dir/checkpoints
  StepBudget time_warmup(double budget_seconds);  // fit_steps_to_budget's measurement (every rank: same steps)

  ocl::Context* ctx_;
  TrainConfig config_;
  std::string out_dir_;
  std::string data_fingerprint_;  // data::fingerprint of the training split, recorded in every checkpoint
  data::Dataset dataset_;
  graph::GraphSpec spec_;
  MemoryPlan memory_;
  std::vector<std::unique_ptr<mlp::Network>> networks_;
  std::vector<std::unique_ptr<mlp::Adam>> optimisers_;
  std::vector<std::unique_ptr<mlp::GridTable>> grids_;
  std::vector<std::unique_ptr<mlp::Adam>> grid_optimisers_;  // one per grid
  std::unique_ptr<Impl> impl_;
  int64_t step_ = 0;             // steps completed
  double seconds_before_ = 0.0;  // training seconds of earlier runs (resume)
};

}  // namespace mipnerf::train
