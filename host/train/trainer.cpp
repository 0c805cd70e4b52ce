// The training loop: batches on the device, the host graph per chunk, Adam, logs and checkpoints.
#include "train/trainer.hpp"

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>

#include "core/error.hpp"
#include "data/device_dataset.hpp"
#include "data/fingerprint.hpp"
#include "parallel/world.hpp"
#include "graph/graph.hpp"
#include "io/atomic_file.hpp"
#include "gemm/gemm_backend.hpp"
#include "ops/batch.hpp"
#include "train/checkpoint.hpp"
#include "train/data_parallel.hpp"
#include "train/model.hpp"
#include "train/run_log.hpp"
#include "train/train_step.hpp"

namespace mipnerf::train {
namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

// The training clock of a run (its wall time minus the time spent scoring val views, plus the runs before a resume)
// and the window rays/s is measured over.
struct Trainer::RunTiming {
  Clock::time_point start = Clock::now();
  double seconds_before = 0.0;  // training seconds of the runs before a resume
  double val_seconds = 0.0;     // spent scoring val views in this run: not training time
  Clock::time_point window_start = Clock::now();
  int64_t window_steps = 0;

  double this_run() const { return std::chrono::duration<double>(Clock::now() - start).count() - val_seconds; }
  double so_far() const { return seconds_before + this_run(); }
  void restart_window() {
    window_start = Clock::now();
    window_steps = 0;
  }
};

struct Trainer::Impl {
  data::DeviceDataset device_data;
  ops::BatchArrays batch;
  graph::Graph graph;
  std::ofstream csv;
  std::ofstream val_csv;        // val_log.csv: open when val_every > 0
  std::vector<float> reduce;    // the gradient sum's host buffer (mpirun), reused between steps

  Impl(ocl::Context& ctx, const data::Split& split, size_t batch_rays, const graph::GraphSpec& spec,
       std::vector<mlp::Network*> networks, std::vector<mlp::GridTable*> grids, size_t chunk_rays)
      : device_data(ctx, split),
        batch(ctx, batch_rays),
        graph(ctx, spec, std::move(networks), std::move(grids), graph::GraphMode::training, chunk_rays, batch_rays) {}
};

Trainer::Trainer(ocl::Context& ctx, const TrainConfig& config, const std::string& data_path, const std::string& out_dir,
                 bool resume)
    : ctx_(&ctx), config_(config), out_dir_(out_dir) {
  validate(config_);
  LogFn log = [&ctx](LogLevel level, const std::string& message) { ctx.log(level, message); };
  data::LoadOptions options = load_options(config_, data_path, {"train"});
  options.log = log;
  dataset_ = data::load_dataset(data_path, options);
  const data::Split& train = dataset_.split("train");
  data_fingerprint_ = data::fingerprint(train);
  const bool multiscale_data = train.num_scales() > 1;
  spec_ = make_graph_spec(config_, multiscale_data);
  // An NDC run records the map its cameras share (after the training spec is made: training keeps each camera's own,
  // the same value, so its kernels are the ones before this record existed), for renders at another field of view.
  if (config_.ray_shape == RayShape::cylinder && !(config_.ndc_projection[0] > 0.0) && train.num_images() > 0) {
    const Camera& first = train.cameras[0];
    config_.ndc_projection = {
        static_cast<double>(2.0f * static_cast<float>(first.focal_x_px) / static_cast<float>(first.width_px)),
        static_cast<double>(2.0f * static_cast<float>(first.focal_y_px) / static_cast<float>(first.height_px))};
  }
  // The plan comes before the first allocation on the device: what does not fit stops here, naming the setting.
  const size_t batch_rays = static_cast<size_t>(config_.batch_size);
  if (static_cast<size_t>(parallel::world().size()) > batch_rays) {
    throw parallel::CollectiveError("batch_size " + std::to_string(batch_rays) + " is smaller than the " +
                                std::to_string(parallel::world().size()) +
                                " ranks: each rank needs rays of the batch; raise batch_size or start fewer ranks");
  }
  memory_ = plan_memory(spec_, ctx.device_info(), batch_rays, training_fixed_bytes(train, spec_, batch_rays),
                        static_cast<size_t>(config_.chunk_rays), true);
  if (!spec_.grids.empty() && parallel::world().distributed()) {
    throw parallel::CollectiveError("the zipnerf model trains in one process for now (its grids' gradients are not "
                                    "summed over ranks yet): run it without mpirun");
  }
  networks_ = make_networks(ctx, spec_, config_.gemm_backend);
  mlp::AdamHyper hyper;
  hyper.grad_max_norm = config_.grad_max_norm;
  hyper.beta2 = config_.adam_beta2;
  hyper.epsilon = static_cast<float>(config_.adam_epsilon);
  for (const auto& network : networks_) {
    optimisers_.push_back(std::make_unique<mlp::Adam>(ctx, network->parameter_count(), hyper));
  }
  grids_ = make_grids(ctx, spec_);
  for (const auto& grid : grids_) {
    grid_optimisers_.push_back(std::make_unique<mlp::Adam>(ctx, grid->parameter_count(), hyper));
  }

  impl_ = std::make_unique<Impl>(ctx, train, batch_rays, spec_, network_pointers(), grid_pointers(),
                                 memory_.chunk_rays);

  // Rank 0 alone touches the output folder (under mpirun the others read the checkpoint it chose).
  const parallel::World& world = parallel::world();
  std::string start_from;  // the checkpoint to resume from; "" = step 0
  std::string refusal;     // why the run cannot start here
  if (world.is_root()) start_from = choose_start(resume, refusal);
  world.broadcast(refusal);
  if (!refusal.empty()) throw parallel::CollectiveError(refusal);
  world.broadcast(start_from);
  if (!start_from.empty()) restore(start_from);
  check_ranks_agree(config_, train, networks_, optimisers_);
  if (!world.is_root()) return;
  io::write_bytes_atomically((fs::path(out_dir_) / "config.json").string(), to_json(config_) + "\n");

  open_log(impl_->csv, (fs::path(out_dir_) / "train_log.csv").string(), step_, kTrainingLogHeader);
  if (config_.val_every > 0) {
    open_log(impl_->val_csv, (fs::path(out_dir_) / "val_log.csv").string(), step_, std::string(kValLogColumns) + "\n");
  }
}

std::string Trainer::choose_start(bool resume, std::string& refusal) {
  fs::create_directories(out_dir_);
  LogFn log = [this](LogLevel level, const std::string& message) { ctx_->log(level, message); };
  const std::string checkpoints = checkpoint_folder();
  const auto existing = list_checkpoints(checkpoints);
  io::remove_stale_temporaries(checkpoints, log);
  io::remove_stale_temporaries(out_dir_, log);
  if (resume && !existing.empty()) {
    const VerifiedCheckpoint newest = newest_verified_checkpoint(checkpoints);
    for (const auto& skipped : newest.skipped) ctx_->log(LogLevel::warning, "--resume: skipped " + skipped);
    if (newest.path.empty()) {
      refusal = "--resume: none of the " + std::to_string(existing.size()) + " checkpoints in " + checkpoints +
                " verifies (above); start a new --out, or train from scratch here after removing them";
    }
    return newest.path;
  }
  if (resume) {
    ctx_->log(LogLevel::info, "--resume: no checkpoint yet in " + checkpoints + "; starting at step 0");
  } else if (!existing.empty()) {
    refusal = out_dir_ + " already holds checkpoints (newest: step " + std::to_string(existing.back().first) +
              "): pass --resume to continue, or choose another --out";
  }
  return "";
}

Trainer::~Trainer() = default;

size_t Trainer::parameter_count() const {
  size_t n = 0;
  for (const auto& network : networks_) n += network->parameter_count();
  for (const auto& grid : grids_) n += grid->parameter_count();
  return n;
}

std::vector<mlp::Network*> Trainer::network_pointers() const { return mlp::network_pointers(networks_); }
std::vector<mlp::GridTable*> Trainer::grid_pointers() const { return mlp::grid_pointers(grids_); }

std::string Trainer::checkpoint_folder() const { return (fs::path(out_dir_) / "checkpoints").string(); }

std::string Trainer::save_checkpoint() {
  const std::string path = checkpoint_path(checkpoint_folder(), step_);
  if (!parallel::world().is_root()) return path;  // rank 0 writes; every rank holds the same state
  CheckpointRecord record;
  record.step = step_;
  record.train_seconds = seconds_before_;
  record.multiscale_data = dataset_.split("train").num_scales() > 1;
  record.device = ctx_->device_info().name;
  // Where the training data was (absolute), so render and eval find the scene without being told.
  record.data_path = fs::absolute(dataset_.path).lexically_normal().string();
  record.data_fingerprint = data_fingerprint_;
  try {
    save_training_checkpoint(path, config_, record, networks_, optimisers_,
                             GridParts{&grids_, &grid_optimisers_});
  } catch (const Error& e) {
    // A full disk (or a file-size limit) stops the run here; the atomic write left the older checkpoints as
    // they were, so the message says which one a --resume continues from.
    const auto saved = list_checkpoints(checkpoint_folder());
    throw Error(std::string(e.what()) + "; " +
                (saved.empty() ? std::string("no checkpoint of this run was written yet")
                               : "the previous checkpoint " + saved.back().second + " is intact") +
                ": free some space (or raise the file size limit), then continue with --resume");
  }
  prune_checkpoints(checkpoint_folder(), config_.keep_checkpoints);
  return path;
}

void Trainer::restore(const std::string& path) {
  LogFn log = [this](LogLevel level, const std::string& message) { ctx_->log(level, message); };
  const CheckpointRecord record =
      restore_training_checkpoint(path, config_, {dataset_.path, data_fingerprint_}, networks_, optimisers_, log,
                                  GridParts{&grids_, &grid_optimisers_});
  step_ = record.step;
  seconds_before_ = record.train_seconds;
  ctx_->log(LogLevel::info, "resuming from " + path + " at step " + std::to_string(step_));
}

StepBudget Trainer::time_warmup(double budget_seconds) {
  StepParts parts = step_parts();
  StepBudget budget;
  budget.budget_seconds = budget_seconds;
  const auto cold_start = Clock::now();
  train_step(parts, 1, {}, impl_->reduce);
  ctx_->finish();  // a step's last kernels (Adam) are asynchronous: time them inside the step they belong to
  budget.cold_step_seconds = std::chrono::duration<double>(Clock::now() - cold_start).count();
  const auto warm_start = Clock::now();
  // Under mpirun every rank takes the same steps (each step is collective): the stop is any rank's.
  while (!any_rank(warmup_done(budget.warm_steps, budget.warm_seconds, budget_seconds))) {
    train_step(parts, budget.warm_steps + 2, {}, impl_->reduce);
    ctx_->finish();
    ++budget.warm_steps;
    budget.warm_seconds = std::chrono::duration<double>(Clock::now() - warm_start).count();
  }
  budget.seconds_per_step = budget.warm_seconds / static_cast<double>(budget.warm_steps);
  return budget;
}

StepBudget Trainer::fit_steps_to_budget(double budget_seconds) {
  check_budget_minutes(budget_seconds / 60.0);
  if (step_ != 0) {
    throw Error("a time budget sizes a new run, but this run is at step " + std::to_string(step_) +
                ": it keeps the " + std::to_string(config_.steps) + " steps it recorded (give --steps to change them)");
  }
  // The warm-up's steps are thrown away: what they changed is put back, so step 1 starts from the initial state.
  std::vector<std::vector<float>> initial_params;
  std::vector<mlp::AdamState> initial_moments;
  for (const auto& network : networks_) initial_params.push_back(network->download_params());
  for (const auto& optimiser : optimisers_) initial_moments.push_back(optimiser->state());
  std::vector<std::vector<float>> initial_tables;  // Zip-NeRF's grids and their optimisers, likewise
  std::vector<mlp::AdamState> initial_grid_moments;
  for (const auto& grid : grids_) initial_tables.push_back(grid->download_params());
  for (const auto& optimiser : grid_optimisers_) initial_grid_moments.push_back(optimiser->state());
  StepBudget budget = time_warmup(budget_seconds);
  for (size_t i = 0; i < networks_.size(); ++i) networks_[i]->upload_params(initial_params[i]);
  for (size_t i = 0; i < optimisers_.size(); ++i) optimisers_[i]->restore(initial_moments[i]);
  for (size_t i = 0; i < grids_.size(); ++i) grids_[i]->upload_params(initial_tables[i]);
  for (size_t i = 0; i < grid_optimisers_.size(); ++i) grid_optimisers_[i]->restore(initial_grid_moments[i]);
  // Rank 0's measurement decides for every rank (each measured its own clock).
  std::string measured = budget.to_json().dump();
  parallel::world().broadcast(measured);
  const nlohmann::json chosen = nlohmann::json::parse(measured);
  budget.cold_step_seconds = chosen.at("cold_step_seconds").get<double>();
  budget.warm_steps = chosen.at("warm_steps").get<int64_t>();
  budget.warm_seconds = chosen.at("warm_seconds").get<double>();
  budget.seconds_per_step = chosen.at("seconds_per_step").get<double>();
  budget.steps = steps_for_budget(budget_seconds, budget.warmup_seconds(), budget.seconds_per_step);
  config_.steps = budget.steps;
  config_.time_budget = budget.describe();
  validate(config_);
  seconds_before_ = budget.warmup_seconds();
  if (parallel::world().is_root()) {
    io::write_bytes_atomically((fs::path(out_dir_) / "config.json").string(), to_json(config_) + "\n");
    io::write_bytes_atomically((fs::path(out_dir_) / "time_budget.json").string(), budget.to_json().dump(2) + "\n");
  }
  return budget;
}

StepParts Trainer::step_parts() {
  return StepParts{*ctx_,     config_,     spec_,  impl_->device_data, impl_->batch,       impl_->graph,
                   networks_, optimisers_, grids_, grid_optimisers_,   memory_.chunk_rays};
}

StepOutcome Trainer::profiled_step(StepParts& parts, int64_t step, const TrainHooks& hooks) {
  ocl::StageProfiler* profiler = ctx_->profiler();
  if (profiler) profiler->begin_step();
  StepOutcome outcome = train_step(parts, step, hooks.after_backward, impl_->reduce);
  if (profiler) profiler->end_step(*ctx_);
  return outcome;
}

void Trainer::note_skipped_step(int64_t step, int consecutive_bad, TrainResult& result) {
  ++result.skipped_steps;
  ctx_->log(LogLevel::warning, "step " + std::to_string(step) + ": non-finite loss or gradients; the update was skipped");
  if (consecutive_bad < config_.max_bad_steps) return;
  const auto saved = list_checkpoints(checkpoint_folder());
  throw parallel::CollectiveError("training stopped at step " + std::to_string(step) + " after " +
                              std::to_string(consecutive_bad) + " consecutive non-finite steps; the last good "
                              "checkpoint is " + (saved.empty() ? std::string("none") : saved.back().second) +
                              "; try a lower lr_init or set grad_max_norm");
}

StepReport Trainer::report_of(const StepOutcome& outcome, RunTiming& timing) const {
  StepReport report;
  report.step = step_;
  report.total_steps = config_.steps;
  report.loss = ops::total_loss(outcome.losses, static_cast<float>(config_.coarse_loss_mult));
  report.psnr = outcome.losses.back().psnr();
  report.learning_rate = outcome.learning_rate;
  report.skipped = !outcome.applied;
  ++timing.window_steps;
  const double window = std::chrono::duration<double>(Clock::now() - timing.window_start).count();
  report.rays_per_second = window > 0 ? static_cast<double>(timing.window_steps * config_.batch_size) / window : 0.0;
  report.train_seconds = timing.so_far();
  return report;
}

// train_log.csv: every log_every steps, after a skipped step and at the last.
void Trainer::log_step(const StepReport& r, RunTiming& timing) {
  if (!(r.step % config_.log_every == 0 || r.skipped || r.step == config_.steps)) return;
  if (parallel::world().is_root()) {
    impl_->csv << r.step << "," << std::setprecision(6) << r.train_seconds << "," << std::setprecision(8) << r.loss
               << "," << r.psnr << "," << r.learning_rate << "," << std::setprecision(6) << r.rays_per_second << ","
               << (r.skipped ? 1 : 0) << "\n"
               << std::flush;
  }
  timing.restart_window();
}

// val_log.csv: every val_every steps and at the last, the scoring kept out of the training clock.
void Trainer::score_val_if_due(const TrainHooks& hooks, RunTiming& timing) {
  if (config_.val_every <= 0 || !hooks.score_val) return;
  if (step_ % config_.val_every != 0 && step_ != config_.steps) return;
  const auto start = Clock::now();
  const ValScore score = hooks.score_val(*this);
  const double took = std::chrono::duration<double>(Clock::now() - start).count();
  timing.val_seconds += took;
  if (parallel::world().is_root()) {
    impl_->val_csv << step_ << "," << std::setprecision(6) << timing.so_far() << "," << std::setprecision(8)
                   << score.psnr << "," << score.ssim << "," << score.images << "," << std::setprecision(6) << took
                   << "\n"
                   << std::flush;
  }
  timing.restart_window();  // the next rays/s window starts after the scoring
}

std::string Trainer::checkpoint_now(const RunTiming& timing) {
  seconds_before_ = timing.so_far();  // what the checkpoint records
  const std::string path = save_checkpoint();
  seconds_before_ = timing.seconds_before;
  return path;
}

TrainResult Trainer::run(const TrainHooks& hooks) {
  RunTiming timing;
  timing.seconds_before = seconds_before_;
  StepParts parts = step_parts();
  TrainResult result;
  int consecutive_bad = 0;
  int64_t last_saved = -1;
  while (step_ < config_.steps) {
    const StepOutcome outcome = profiled_step(parts, step_ + 1, hooks);
    ++step_;
    consecutive_bad = outcome.applied ? 0 : consecutive_bad + 1;
    if (!outcome.applied) note_skipped_step(step_, consecutive_bad, result);
    const StepReport report = report_of(outcome, timing);
    result.final_psnr = report.psnr;
    // The periodic actions: the log row, the val score, the checkpoint, a stop request (the same on every rank).
    log_step(report, timing);
    if (hooks.on_step) hooks.on_step(report);
    score_val_if_due(hooks, timing);
    const bool stop = any_rank(hooks.should_stop && hooks.should_stop());
    // Periodic checkpoints only after good steps, so a non-finite streak never replaces (or prunes) the last good
    // one; the final and the interrupt checkpoints are always written.
    if ((outcome.applied && step_ % config_.checkpoint_every == 0) || step_ == config_.steps || stop) {
      result.checkpoint = checkpoint_now(timing);
      last_saved = step_;
    }
    if (stop) {
      result.interrupted = step_ < config_.steps;
      break;
    }
  }
  // Nothing left to do (e.g. a resumed, finished run): make sure a checkpoint of the last step exists.
  if (last_saved != step_) result.checkpoint = checkpoint_now(timing);
  result.last_step = step_;
  result.seconds_this_run = timing.this_run();
  result.train_seconds = timing.so_far();
  seconds_before_ = result.train_seconds;
  return result;
}

}  // namespace mipnerf::train
