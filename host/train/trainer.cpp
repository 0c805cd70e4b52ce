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
#include "dist/world.hpp"
#include "graph/graph.hpp"
#include "io/atomic_file.hpp"
#include "gemm/gemm_backend.hpp"
#include "ops/batch.hpp"
#include "train/checkpoint.hpp"
#include "train/model.hpp"

namespace mipnerf::train {
namespace fs = std::filesystem;

namespace {

mlp::LrSchedule schedule_of(const TrainConfig& c) {
  mlp::LrSchedule s;
  s.lr_init = c.lr_init;
  s.lr_final = c.lr_final;
  s.max_steps = c.steps;
  s.warmup_steps = c.lr_warmup_steps;
  s.warmup_mult = c.lr_warmup_mult;
  return s;
}

// On resume, the log keeps the rows of the steps the checkpoint holds: rows after it (logged before an interrupt,
// about to be trained again) and a row cut short by a kill are dropped, so each step appears once. Atomic.
constexpr const char* kTrainingLogHeader = "step,wall_seconds,loss,psnr,learning_rate,rays_per_second,skipped\n";

void trim_log(const std::string& csv_path, int64_t step, const std::string& header_line) {
  std::ifstream in(csv_path);
  std::string kept, line;
  bool header = true;
  while (std::getline(in, line)) {
    if (in.eof()) break;  // the last line has no newline: cut short
    if (!header) {
      char* end = nullptr;
      const long long row_step = std::strtoll(line.c_str(), &end, 10);
      if (end == line.c_str() || *end != ',' || row_step > step) continue;
    }
    header = false;
    kept += line + "\n";
  }
  io::write_bytes_atomically(csv_path, kept.empty() ? header_line : kept);
}

// Opens a run's CSV log: appended to (its rows after `step` dropped) when resuming, else started anew.
void open_log(std::ofstream& csv, const std::string& csv_path, int64_t step, const std::string& header_line) {
  const bool append = step > 0 && fs::exists(csv_path);
  if (append) trim_log(csv_path, step, header_line);
  csv.open(csv_path, append ? std::ios::app : std::ios::trunc);
  if (!csv) throw Error(csv_path + ": cannot write this log; check the folder's permissions and free space");
  if (!append) csv << header_line << std::flush;
}

// What the ranks of a data-parallel run must share before the first step: the same settings (execution ones too:
// chunking decides which rays each rank trains), the same training data and the same parameters and Adam state.
uint64_t config_fingerprint(const TrainConfig& config) {
  const std::string text = to_json(config);
  return dist::fnv1a(text.data(), text.size());
}

uint64_t data_fingerprint(const data::Split& split) {
  const std::vector<float> cameras = pack_cameras(split.cameras);
  uint64_t hash = dist::fnv1a(cameras.data(), cameras.size() * sizeof(float));
  hash = dist::fnv1a(split.scale_levels.data(), split.scale_levels.size() * sizeof(uint32_t), hash);
  return dist::fnv1a(split.rgb.data(), split.rgb.size() * sizeof(float), hash);
}

uint64_t parameter_fingerprint(const std::vector<std::unique_ptr<mlp::Network>>& networks,
                               const std::vector<std::unique_ptr<mlp::Adam>>& optimisers) {
  uint64_t hash = dist::fnv1a(nullptr, 0);
  for (size_t i = 0; i < networks.size(); ++i) {
    const std::vector<float> params = networks[i]->download_params();
    const mlp::AdamState state = optimisers[i]->state();
    hash = dist::fnv1a(params.data(), params.size() * sizeof(float), hash);
    hash = dist::fnv1a(state.m.data(), state.m.size() * sizeof(float), hash);
    hash = dist::fnv1a(state.v.data(), state.v.size() * sizeof(float), hash);
    hash = dist::fnv1a(&state.step, sizeof(state.step), hash);
  }
  return hash;
}

// Under mpirun: every rank checks it has rank 0's settings, data and parameters (at the start and after a resume),
// and all stop with one message otherwise.
void check_ranks_agree(const TrainConfig& config, const data::Split& train,
                       const std::vector<std::unique_ptr<mlp::Network>>& networks,
                       const std::vector<std::unique_ptr<mlp::Adam>>& optimisers) {
  if (!dist::world().distributed()) return;
  dist::require_same_on_every_rank(config_fingerprint(config), "the training settings",
                                   "start every rank with the same command line and --config file");
  dist::require_same_on_every_rank(data_fingerprint(train), "the training data (cameras and pixels)",
                                   "give every rank the same --data, with identical files on every host");
  dist::require_same_on_every_rank(parameter_fingerprint(networks, optimisers),
                                   "the parameters and Adam state",
                                   "every rank must see the same --out folder (a shared filesystem), so that "
                                   "--resume reads the same checkpoint everywhere");
}

// The gradients of every network and the step's loss sums, summed over the ranks (one MPI_Allreduce of floats,
// one of doubles). Each rank's gradients cover its share of the batch and are already divided by the batch's
// global Σ lossmult (graph begin_step), so their sum is the single-process gradient, up to summation order.
void sum_over_ranks(ocl::Context& ctx, std::vector<std::unique_ptr<mlp::Network>>& networks,
                    std::vector<ops::LevelLoss>& losses, std::vector<float>& flat) {
  size_t total = 0;
  for (const auto& network : networks) total += network->parameter_count();
  flat.resize(total);
  size_t at = 0;
  for (auto& network : networks) {
    network->grads().download(ctx, flat.data() + at, network->parameter_count());
    at += network->parameter_count();
  }
  dist::world().sum_in_place(flat.data(), flat.size());
  at = 0;
  for (auto& network : networks) {
    network->grads().upload(ctx, flat.data() + at, network->parameter_count());
    at += network->parameter_count();
  }
  std::vector<double> sums;
  for (const auto& l : losses) {
    sums.push_back(l.weighted_sse);
    sums.push_back(l.plain_sse);
  }
  dist::world().sum_in_place(sums.data(), sums.size());
  for (size_t i = 0; i < losses.size(); ++i) {
    losses[i].weighted_sse = sums[2 * i];
    losses[i].plain_sse = sums[2 * i + 1];
  }
}

// True on every rank when any rank asks to stop (Ctrl-C, SIGTERM): all stop after the same step.
bool any_rank(bool flag) {
  double value = flag ? 1.0 : 0.0;
  dist::world().sum_in_place(&value, 1);
  return value > 0.0;
}

}  // namespace

struct Trainer::Impl {
  data::DeviceDataset device_data;
  ops::BatchArrays batch;
  graph::Graph graph;
  std::ofstream csv;
  std::ofstream val_csv;  // val_log.csv: open when val_every > 0

  Impl(ocl::Context& ctx, const data::Split& split, size_t batch_rays, const graph::GraphSpec& spec,
       std::vector<mlp::Network*> networks, size_t chunk_rays)
      : device_data(ctx, split),
        batch(ctx, batch_rays),
        graph(ctx, spec, std::move(networks), graph::GraphMode::training, chunk_rays, batch_rays) {}
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
  const bool multiscale_data = train.num_scales() > 1;
  spec_ = make_graph_spec(config_, multiscale_data);
  // The plan comes before the first allocation on the device: what does not fit stops here, naming the setting.
  const size_t batch_rays = static_cast<size_t>(config_.batch_size);
  if (static_cast<size_t>(dist::world().size()) > batch_rays) {
    throw dist::CollectiveError("batch_size " + std::to_string(batch_rays) + " is smaller than the " +
                                std::to_string(dist::world().size()) +
                                " ranks: each rank needs rays of the batch; raise batch_size or start fewer ranks");
  }
  memory_ = plan_memory(spec_, ctx.device_info(), batch_rays, training_fixed_bytes(train, spec_, batch_rays),
                        static_cast<size_t>(config_.chunk_rays), true);
  networks_ = make_networks(ctx, spec_, config_.gemm_backend);
  for (const auto& network : networks_) {
    mlp::AdamHyper hyper;
    hyper.grad_max_norm = config_.grad_max_norm;
    optimisers_.push_back(std::make_unique<mlp::Adam>(ctx, network->parameter_count(), hyper));
  }

  impl_ = std::make_unique<Impl>(ctx, train, batch_rays, spec_, network_pointers(), memory_.chunk_rays);

  // Rank 0 alone touches the output folder (under mpirun the others read the checkpoint it chose).
  const dist::World& world = dist::world();
  std::string start_from;  // the checkpoint to resume from; "" = step 0
  std::string refusal;     // why the run cannot start here
  if (world.is_root()) start_from = choose_start(resume, refusal);
  world.broadcast(refusal);
  if (!refusal.empty()) throw dist::CollectiveError(refusal);
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
  return n;
}

std::vector<mlp::Network*> Trainer::network_pointers() const { return mlp::network_pointers(networks_); }

std::string Trainer::checkpoint_folder() const { return (fs::path(out_dir_) / "checkpoints").string(); }

std::string Trainer::save_checkpoint() {
  const std::string path = checkpoint_path(checkpoint_folder(), step_);
  if (!dist::world().is_root()) return path;  // rank 0 writes; every rank holds the same state
  CheckpointRecord record;
  record.step = step_;
  record.train_seconds = seconds_before_;
  record.multiscale_data = dataset_.split("train").num_scales() > 1;
  record.device = ctx_->device_info().name;
  // Where the training data was (absolute), so render and eval find the scene without being told.
  record.data_path = fs::absolute(dataset_.path).lexically_normal().string();
  try {
    save_training_checkpoint(path, config_, record, networks_, optimisers_);
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
  const CheckpointRecord record = restore_training_checkpoint(path, config_, networks_, optimisers_, log);
  step_ = record.step;
  seconds_before_ = record.train_seconds;
  ctx_->log(LogLevel::info, "resuming from " + path + " at step " + std::to_string(step_));
}

TrainResult Trainer::run(const TrainHooks& hooks) {
  using clock = std::chrono::steady_clock;
  const auto run_start = clock::now();
  const mlp::LrSchedule schedule = schedule_of(config_);
  const size_t batch_rays = static_cast<size_t>(config_.batch_size);
  const size_t chunk = memory_.chunk_rays;
  const ops::BatchOptions batch_options{config_.seed, config_.batching};
  auto& batch = impl_->batch;
  const graph::RaySource source{impl_->device_data.cameras(), batch.camera_ids, batch.pixel_ids};
  const graph::TrainTargets targets{batch.target_rgb, spec_.loss.multiscale ? &batch.lossmult : nullptr};
  // Data parallel (mpirun): this rank trains a contiguous share of the batch's ray indices, in chunks of up to
  // `chunk` rays; every rank draws the whole batch (cheap), so Σ lossmult stays global. When the share is a multiple
  // of the chunk, each chunk is a single-process chunk bit for bit.
  const dist::World& world = dist::world();
  const std::vector<size_t> shares = dist::share_offsets(batch_rays, world.size());
  const size_t my_first_ray = shares[static_cast<size_t>(world.rank())];
  const size_t my_end_ray = shares[static_cast<size_t>(world.rank()) + 1];
  std::vector<float> reduce_buffer;

  TrainResult result;
  int consecutive_bad = 0;
  int64_t last_saved = -1;
  auto window_start = clock::now();
  int64_t window_steps = 0;
  double val_seconds = 0.0;  // spent scoring val views in this run: not training time
  // Training seconds of this run (val scoring excluded), and with those of the runs before a resume.
  auto seconds_this_run = [&] {
    return std::chrono::duration<double>(clock::now() - run_start).count() - val_seconds;
  };
  auto seconds_so_far = [&] { return seconds_before_ + seconds_this_run(); };

  while (step_ < config_.steps) {
    const int64_t step = step_ + 1;
    ocl::StageProfiler* profiler = ctx_->profiler();
    if (profiler) profiler->begin_step();
    double lossmult_sum = static_cast<double>(batch_rays);
    {
      ocl::StageScope stage(*ctx_, "batch");
      ops::batch_sample(*ctx_, impl_->device_data, batch_options, static_cast<uint32_t>(step), batch);
      if (spec_.loss.multiscale) {
        lossmult_sum = 0.0;
        for (float m : batch.lossmult.download(*ctx_)) lossmult_sum += m;
      }
    }
    impl_->graph.begin_step(batch_rays, lossmult_sum);
    for (size_t first = my_first_ray; first < my_end_ray; first += chunk) {
      impl_->graph.train_chunk(source, {first, std::min(chunk, my_end_ray - first)}, targets,
                               {config_.seed, static_cast<uint32_t>(step)});
    }
    std::vector<ops::LevelLoss> losses = impl_->graph.end_step();
    if (hooks.after_backward) hooks.after_backward(step, networks_);
    if (world.distributed()) {
      // Host work after end_step drained the queue: the gradients' copies to and from the host and the sums.
      ocl::StageScope reduce_stage(*ctx_, "allreduce (gradient copies + MPI)");
      ocl::HostTimer reduce_timer(*ctx_);
      sum_over_ranks(*ctx_, networks_, losses, reduce_buffer);
    }

    bool finite = true;
    for (const auto& l : losses) finite = finite && l.finite();
    ocl::StageScope adam_stage(*ctx_, "adam");
    std::vector<mlp::GradientStats> stats;
    for (size_t i = 0; i < networks_.size(); ++i) {
      stats.push_back(optimisers_[i]->gradient_stats(networks_[i]->grads()));
      finite = finite && stats.back().finite();
    }
    const double lr = mlp::learning_rate(schedule, step);
    if (finite) {
      for (size_t i = 0; i < networks_.size(); ++i) {
        optimisers_[i]->step(networks_[i]->params(), networks_[i]->grads(), lr, &stats[i]);
      }
      consecutive_bad = 0;
    } else {
      ++result.skipped_steps;
      ++consecutive_bad;
      ctx_->log(LogLevel::warning,
                "step " + std::to_string(step) + ": non-finite loss or gradients; the update was skipped");
      if (consecutive_bad >= config_.max_bad_steps) {
        const auto saved = list_checkpoints(checkpoint_folder());
        throw dist::CollectiveError("training stopped at step " + std::to_string(step) + " after " + std::to_string(consecutive_bad) +
                    " consecutive non-finite steps; the last good checkpoint is " +
                    (saved.empty() ? std::string("none") : saved.back().second) +
                    "; try a lower lr_init or set grad_max_norm");
      }
    }
    if (profiler) profiler->end_step(*ctx_);
    step_ = step;
    ++window_steps;

    StepReport report;
    report.step = step;
    report.total_steps = config_.steps;
    report.loss = ops::total_loss(losses, static_cast<float>(config_.coarse_loss_mult));
    report.psnr = losses.back().psnr();
    report.learning_rate = lr;
    report.skipped = !finite;
    const double window = std::chrono::duration<double>(clock::now() - window_start).count();
    report.rays_per_second = window > 0 ? static_cast<double>(window_steps * batch_rays) / window : 0.0;
    report.train_seconds = seconds_so_far();
    result.final_psnr = report.psnr;
    if (world.is_root() && (step % config_.log_every == 0 || !finite || step == config_.steps)) {
      impl_->csv << step << "," << std::setprecision(6) << report.train_seconds << "," << std::setprecision(8)
                 << report.loss << "," << report.psnr << "," << lr << "," << std::setprecision(6)
                 << report.rays_per_second << "," << (finite ? 0 : 1) << "\n"
                 << std::flush;
      window_start = clock::now();
      window_steps = 0;
    }
    if (hooks.on_step) hooks.on_step(report);
    if (config_.val_every > 0 && hooks.score_val && (step % config_.val_every == 0 || step == config_.steps)) {
      const auto val_start = clock::now();
      const ValScore score = hooks.score_val(*this);
      const double took = std::chrono::duration<double>(clock::now() - val_start).count();
      val_seconds += took;
      if (world.is_root()) impl_->val_csv << step << "," << std::setprecision(6) << seconds_so_far() << "," << std::setprecision(8)
                     << score.psnr << "," << score.ssim << "," << score.images << "," << std::setprecision(6) << took
                     << "\n"
                     << std::flush;
      window_start = clock::now();  // the next rays/s window starts after the scoring
      window_steps = 0;
    }

    const bool stop = any_rank(hooks.should_stop && hooks.should_stop());
    // Periodic checkpoints only after good steps, so a non-finite streak never replaces (or prunes) the
    // last good one; the final and the interrupt checkpoints are always written.
    if ((finite && step % config_.checkpoint_every == 0) || step == config_.steps || stop) {
      seconds_before_ = seconds_so_far();
      result.checkpoint = save_checkpoint();
      seconds_before_ -= seconds_this_run();
      last_saved = step;
    }
    if (stop) {
      result.interrupted = step < config_.steps;
      break;
    }
  }
  if (last_saved != step_) {  // nothing left to do (e.g. resumed a finished run): make sure a checkpoint exists
    seconds_before_ = seconds_so_far();
    result.checkpoint = save_checkpoint();
    seconds_before_ -= seconds_this_run();
  }
  result.last_step = step_;
  result.seconds_this_run = seconds_this_run();
  result.train_seconds = seconds_before_ + result.seconds_this_run;
  seconds_before_ = result.train_seconds;
  return result;
}

}  // namespace mipnerf::train
