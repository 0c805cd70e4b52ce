// `mipnerf-cl train`: train a scene (the built-in procedural one by default), then render and score the
// val views, so a run ends with an image, a number, and what it cost.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>

#include "bench/stage_report.hpp"
#include "core/error.hpp"
#include "parallel/world.hpp"
#include "common.hpp"
#include "data/synthetic/procedural.hpp"
#include "eval/report.hpp"
#include "eval/train_and_evaluate.hpp"
#include "io/atomic_file.hpp"
#include "io/checkpoint_file.hpp"
#include "train/checkpoint.hpp"
#include "train/config_file.hpp"
#include "train/scene_effects.hpp"
#include "train/step_budget.hpp"
#include "interrupt.hpp"
#include "progress.hpp"

namespace mipnerf::cli {
namespace fs = std::filesystem;
namespace {

struct TrainArgs {
  std::string data;
  std::string out = "runs/train";
  std::string preset = "quick";
  std::string variant = "mipnerf";
  std::string model;  // --model: the model family's variant bundle (zipnerf picks the fast preset by default)
  bool resume = false;
  bool profile = false;                   // --profile: stage breakdown of steps 2…, in OUT/profile.md
  std::optional<double> minutes;          // --minutes N: the steps of a new run sized to a wall-clock budget
  std::string config_file;                // --config FILE
  std::vector<std::string> sets;          // --set name=value
  std::map<std::string, std::string> flag_values;  // --<setting> value
};

// The settings given explicitly: the config file, then flags, then --set (later ones win).
std::map<std::string, std::string> explicit_settings(const TrainArgs& args, CLI::App& cmd) {
  std::map<std::string, std::string> out;
  if (!args.config_file.empty()) out = train::read_config_file(args.config_file, "--config " + args.config_file);
  for (const auto& s : train::settings()) {
    // --variant names a bundle (a row of the paper's tables), not the `variant` setting (the model family): the
    // bundle is applied by resolve_config. Read as the setting, every bundle but mipnerf and nerf was refused.
    if (s.name == "variant") continue;
    auto* option = cmd.get_option_no_throw("--" + s.name);
    if (option != nullptr && option->count() > 0) out[s.name] = option->as<std::string>();
  }
  for (const auto& [name, value] : parse_set_assignments(args.sets, "num_samples=64")) out[name] = value;
  return out;
}

// The quick start's scene: made once inside the output folder, reused afterwards.
std::string default_scene(const std::string& out_dir) {
  const fs::path scene = fs::path(out_dir) / "scene";
  const parallel::World& world = parallel::world();
  if (!world.is_root()) {  // under mpirun, rank 0 makes it, the others wait for it
    world.barrier();
    return scene.string();
  }
  make_output_folder(out_dir, "--out");
  if (!fs::exists(scene / "transforms_train.json")) {
    std::cerr << "mipnerf-cl: no --data given: generating the built-in procedural scene in " << scene.string() << "\n";
    data::write_procedural_scene(scene.string(), data::SceneOptions{});
  }
  world.barrier();
  return scene.string();
}

// Before the first step: what is being trained.
void print_setup(train::Trainer& trainer, ocl::Context& ctx, const std::string& preset) {
  const auto& config = trainer.config();
  if (!config.scene_effects.empty()) std::cerr << "mipnerf-cl: " << config.scene_effects << "\n";
  if (!config.time_budget.empty()) std::cerr << "mipnerf-cl: " << config.time_budget << "\n";
  std::cerr << "mipnerf-cl: training " << enum_name(config.variant) << " (preset " << preset << ") on " << ctx.device_info().name
            << ": " << trainer.dataset().split("train").num_images() << " images, " << trainer.parameter_count()
            << " parameters, " << trainer.spec().describe() << "\n"
            << "mipnerf-cl: " << trainer.memory().describe() << "\n";
}

std::string step_detail(const train::StepReport& r) {
  char detail[160];
  std::snprintf(detail, sizeof(detail), "loss %.5f  psnr %.2f dB  lr %.2e  %.0f rays/s%s", r.loss, r.psnr,
                r.learning_rate, r.rays_per_second, r.skipped ? "  (skipped: non-finite)" : "");
  return detail;
}

void report_trained(const train::TrainResult& result, const std::string& device) {
  if (result.interrupted) {
    std::cerr << "mipnerf-cl: interrupted at step " << result.last_step << "; checkpoint " << result.checkpoint
              << " (continue with --resume)\n";
  } else {
    std::cerr << "mipnerf-cl: trained " << result.last_step << " steps in " << format_duration(result.train_seconds)
              << " on " << device << "; checkpoint " << result.checkpoint << "\n";
  }
}

// --profile: every step after the first (which builds the kernels) by stage, printed and written to OUT/profile.md.
void write_profile(const ocl::StageProfile& profile, const train::TrainConfig& config, const std::string& device,
                   const std::string& out_dir) {
  if (profile.steps == 0) return;
  const std::string table = bench::stage_profile_markdown(profile, static_cast<size_t>(config.batch_size));
  const std::string path = (fs::path(out_dir) / "profile.md").string();
  io::write_bytes_atomically(path, "# Training step by stage\n\nDevice: " + device + "; " +
                                       std::to_string(config.batch_size) + " rays per step.\n\n" + table);
  std::cerr << "mipnerf-cl: where a step's time goes (also in " << path << "):\n\n" << table << "\n";
}

// The run OUT holds: the header of its newest checkpoint that reads (the trainer reports and sets aside one that does
// not verify), or nothing when it has none.
std::optional<train::CheckpointHeader> run_in(const std::string& out) {
  const auto found = train::list_checkpoints((fs::path(out) / "checkpoints").string());
  for (auto it = found.rbegin(); it != found.rend(); ++it) {
    try {
      return train::read_checkpoint_header(io::read_checkpoint_file(it->second), it->second);
    } catch (const Error&) {
      continue;
    }
  }
  return std::nullopt;
}

// What to train and on which data. A new run: the preset, the variant, the settings given and the effects the data
// calls for. `--resume` without --preset or --variant: the run as its checkpoint recorded it (its settings, and its
// data unless --data is given, which the trainer then checks by content), with the settings given on top (more
// steps, say); nothing is generated, not even the built-in scene.
struct WhatToTrain {
  train::TrainConfig config;
  std::string data_path;
  std::optional<train::CheckpointHeader> previous;  // the run continued, when there is one
};

// --model NAME is --variant NAME for a model family, and with zipnerf the fast preset unless --preset is given.
void apply_model(TrainArgs& args, CLI::App& cmd) {
  if (args.model.empty()) return;
  if (cmd.get_option("--variant")->count() > 0) {
    throw Error("--model and --variant both name the model: give one (--model " + args.model + " is --variant " +
                args.model + ")");
  }
  args.variant = args.model;
  if (args.model == "zipnerf" && cmd.get_option("--preset")->count() == 0) args.preset = "fast";
}

// --minutes: a positive budget, for a new run, and not together with a step count (both would fix the steps).
void check_minutes(const TrainArgs& args, const std::map<std::string, std::string>& settings,
                   const std::optional<train::CheckpointHeader>& previous) {
  if (!args.minutes) return;
  train::check_budget_minutes(*args.minutes);
  if (settings.count("steps") > 0) {
    throw Error("--minutes and steps (" + settings.at("steps") + ", from --steps, --set or --config) both fix the "
                "run's step count: give one of them");
  }
  if (previous) {
    throw Error("--minutes sizes a new run, but " + args.out + " holds one at step " +
                std::to_string(previous->record.step) + " of its recorded " + std::to_string(previous->config.steps) +
                " steps, which --resume continues: drop --minutes (or give --steps N to change the step count)");
  }
}

WhatToTrain what_to_train(const TrainArgs& args, CLI::App& cmd) {
  const auto settings = explicit_settings(args, cmd);
  WhatToTrain what;
  if (args.resume) what.previous = run_in(args.out);
  check_minutes(args, settings, what.previous);
  const bool bundle_given = cmd.get_option("--preset")->count() > 0 || cmd.get_option("--variant")->count() > 0 ||
                            cmd.get_option("--model")->count() > 0;
  if (args.resume && !what.previous && args.data.empty()) {
    throw Error("--resume: " + args.out + " holds no checkpoint to continue (checkpoints/ckpt_*.mnck of `mipnerf-cl "
                "train --out`); check the folder, or give --data to start a run in it");
  }
  if (what.previous && !bundle_given) {
    what.config = what.previous->config;
    for (const auto& [name, value] : settings) train::set_value(what.config, name, value);
    train::validate(what.config);
    what.data_path = args.data.empty() ? what.previous->record.data_path : args.data;
    if (what.data_path.empty()) {
      throw Error("--resume: the checkpoints in " + args.out + " do not record their data (written by an older "
                  "mipnerf-cl): give --data");
    }
    std::error_code ec;
    if (args.data.empty() && !fs::exists(what.data_path, ec)) {
      throw Error("--resume: " + args.out + " was trained on " + what.data_path + ", which is no longer there: give "
                  "--data with the same images (they are checked by content)");
    }
    return what;
  }
  const train::TrainConfig unscened = train::resolve_config(args.preset, args.variant, settings);
  what.data_path = args.data.empty() ? default_scene(args.out) : args.data;
  // The effects the data calls for, where no setting was given (train/scene_effects.hpp).
  std::string scene_line;
  const auto with_scene =
      train::with_scene_effects(train::scene_effects(what.data_path, unscened.factor, unscened.variant), settings,
                                scene_line);
  what.config = train::resolve_config(args.preset, args.variant, with_scene);
  what.config.scene_effects = scene_line;
  return what;
}

// Whether OUT/summary.json holds the scores of a finished run at `step`: a run killed after its last checkpoint,
// during its val evaluation, has none, and its --resume scores them.
bool scores_written_at(const std::string& out, int64_t step) {
  const std::optional<io::Json> summary = eval::read_summary(out);
  try {
    return summary && summary->value("steps", int64_t{-1}) == step && !summary->value("interrupted", true);
  } catch (const std::exception&) {  // a field of another type
    return false;
  }
}

void run_train(TrainArgs& args, CLI::App& cmd) {
  apply_model(args, cmd);
  const WhatToTrain what = what_to_train(args, cmd);
  const train::TrainConfig& config = what.config;
  const std::string& data_path = what.data_path;
  if (what.previous && what.previous->record.step >= config.steps) {
    const bool scored = scores_written_at(args.out, what.previous->record.step);
    if (parallel::world().is_root()) {
      std::cerr << "mipnerf-cl: " << args.out << (scored ? " is already at step " : " is at step ")
                << what.previous->record.step << " of " << config.steps
                << (scored ? ": nothing to train (give --steps N to train further); its scores are in " +
                                 eval::summary_path(args.out)
                           : " but its val scores were never written (stopped while scoring them): scoring them")
                << "\n";
    }
    if (scored) return;
  }
  if (parallel::world().is_root()) make_output_folder(args.out, "--out");  // once the inputs are known good
  auto ctx = open_context(args.profile);
  const std::string device = ctx->device_info().name;
  ocl::StageProfiler profiler;

  std::optional<Progress> train_progress, val_progress;
  std::optional<StopOnInterrupt> stop_on_interrupt;  // from the setup to the end of training
  const bool root = parallel::world().is_root();  // under mpirun, rank 0 alone prints and writes
  eval::TrainAndEvaluateOptions run;
  run.data_path = data_path;
  run.out_dir = args.out;
  run.resume = args.resume;
  if (args.minutes) {
    run.budget_seconds = *args.minutes * 60.0;
    if (root) {
      std::cerr << "mipnerf-cl: --minutes " << *args.minutes << ": timing a warm-up of a few steps to size the run "
                << "(discarded; its time is spent from the budget)\n";
    }
  }
  run.val_image_folder = (fs::path(args.out) / "val").string();
  run.on_setup = [&](train::Trainer& trainer) {
    if (root) print_setup(trainer, *ctx, args.preset);
    // Ctrl-C, or a scheduler's (or mpirun's) SIGTERM: a clean stop, all ranks after the same step.
    stop_on_interrupt.emplace();
    train_progress.emplace("train", trainer.config().steps);  // --minutes: the steps the warm-up chose
  };
  run.hooks.should_stop = [] { return StopOnInterrupt::requested(); };
  run.hooks.on_step = [&](const train::StepReport& r) {
    train_progress->update(r.step, step_detail(r));
    if (args.profile && ctx->profiler() == nullptr) ctx->set_profiler(&profiler);  // from the second step on
  };
  run.on_trained = [&](train::Trainer&, const train::TrainResult& result) {
    stop_on_interrupt.reset();
    train_progress->finish_at(result.last_step);
    ctx->set_profiler(nullptr);
    if (!root) return;
    report_trained(result, device);
    if (args.profile) write_profile(profiler.profile(), config, device, args.out);
  };
  // The val scores during training (val_every): their own progress line (a score of full-size real photos takes
  // a minute on a CPU), kept out of the training line's ETA.
  std::optional<Progress> periodic_val;
  run.on_periodic_val_start = [&](int64_t step, size_t images) {
    if (!root) return;
    periodic_val.emplace("score val at step " + std::to_string(step) + " (" + std::to_string(images) +
                             (images == 1 ? " image)" : " images)"), 1);
    periodic_val->begin_at(0);  // counted in rays from 0
  };
  run.periodic_val_progress = [&](size_t done, size_t total) {
    if (!periodic_val) return;
    periodic_val->set_total(static_cast<int64_t>(total));
    periodic_val->update(static_cast<int64_t>(done));
  };
  run.on_periodic_val_end = [&](double seconds) {
    if (periodic_val) periodic_val->finish();
    periodic_val.reset();
    if (train_progress) train_progress->exclude_from_rate(seconds);
  };
  run.on_val_start = [&](size_t images) { val_progress.emplace("render val", static_cast<int64_t>(images)); };
  run.val_progress = [&](size_t done, size_t) { val_progress->update(static_cast<int64_t>(done)); };
  const eval::TrainAndEvaluateResult result = eval::train_and_evaluate(*ctx, config, run);
  if (result.val && val_progress) val_progress->finish();  // none when the last step's score was the evaluation
  val_progress.reset();  // a failed evaluation's line ends before the warning
  if (!root) return;
  if (!result.val_error.empty()) std::cerr << "mipnerf-cl: warning: no val evaluation: " << result.val_error << "\n";

  const std::string summary =
      eval::write_summary(args.out, result.record, result.train, result.val ? &*result.val : nullptr);
  if (result.val) {
    const eval::SplitScores& scores = *result.val;
    std::printf(
        "val PSNR %.2f dB, SSIM %.4f over %zu images; trained %lld steps in %.1f s; rendering %.2f s/MP on %s\n",
        scores.mean_psnr, scores.mean_ssim, scores.images.size(), static_cast<long long>(result.train.last_step),
        result.train.train_seconds, scores.seconds_per_megapixel(), device.c_str());
    std::printf("images in %s, summary in %s\n", (fs::path(args.out) / "val").string().c_str(), summary.c_str());
  }
}

}  // namespace

void register_train(CLI::App& app) {
  auto args = std::make_shared<TrainArgs>();
  auto* cmd = app.add_subcommand("train", "Train mip-NeRF (or a variant) on a scene, then score its val views");
  cmd->add_option("--data", args->data,
                  "Dataset folder: Blender, multiscale Blender, transforms.json or an LLFF capture (poses_bounds.npy, "
                  "images/); photos without poses: make one with `dataset from-photos`; default: the built-in "
                  "procedural scene, made in OUT/scene");
  cmd->add_option("--out", args->out, "Output folder: checkpoints, logs, config, val renders")->capture_default_str();
  cmd->add_option("--preset", args->preset, "Settings bundle: " + train::describe_bundles())->capture_default_str();
  cmd->add_option("--variant", args->variant,
                  "Model variant, a row of the paper's tables: " + enum_choices<train::Variant>() +
                      " (recorded in OUT/config.json as variant_bundle)")
      ->capture_default_str();
  cmd->add_option("--model", args->model,
                  "Model family: mipnerf (the paper's, the default), nerf, or zipnerf (Zip-NeRF: each frustum's "
                  "multisamples in a multi-resolution hash grid and a tiny MLP; trains far faster per second; the "
                  "fast preset unless --preset is given). Same as --variant NAME")
      ->check(CLI::IsMember({"mipnerf", "nerf", "zipnerf"}));
  cmd->add_flag("--resume", args->resume,
                "Continue the run in --out from its newest checkpoint: its own data and settings (the settings given "
                "change it, e.g. --steps); with --data, that data must hold the same images and cameras");
  cmd->add_option("--minutes", args->minutes,
                  "Train for a wall-clock budget of N minutes (decimals allowed) instead of a step count: after data "
                  "loading, one cold step and then warm steps (at least 3, and at least 2 % of the budget up to 10 s, "
                  "at most 50) are timed and discarded (the networks and Adam are put back); steps = floor((budget - "
                  "warm-up) / measured s/step), and the learning-rate schedule spans them. The choice is recorded "
                  "(config.json time_budget and steps, OUT/time_budget.json, checkpoints), so --resume continues the "
                  "same step count and `--steps` with it reproduces the run bit for bit. A new run only; not with "
                  "--steps (both fix the step count). Checkpoint writes count against the budget; val scoring (val_every) and the final val do not")
      ->type_name("FLOAT");
  cmd->add_flag("--profile", args->profile,
                "Time every step after the first by stage (OpenCL profiling events, host timers); print the table "
                "and write OUT/profile.md. Profiled steps wait for the device at their end, so they run slower");
  cmd->add_option("--set", args->sets,
                  "Any setting as name=value (repeatable); each is a flag too, spelt with dashes or as its name: "
                  "--val-every 5 or --val_every 5");
  cmd->add_option("--config", args->config_file,
                  "TOML/INI file of settings, e.g. `num_samples = 64` (top level or a [train] table); flags win")
      ->check(CLI::ExistingFile);
  for (const auto& s : train::settings()) {
    if (s.name == "variant") continue;  // set through --variant, which also applies the variant's bundle
    cmd->add_option(setting_flag_names(s.name))->description("[" + s.group + "] " + s.help)->type_name(s.type);
  }
  cmd->callback([args, cmd] { run_train(*args, *cmd); });
}

}  // namespace mipnerf::cli
