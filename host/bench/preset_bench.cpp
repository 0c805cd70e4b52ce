// Training steps and a render of one preset, timed through the real trainer and renderer (see preset_bench.hpp).
#include "bench/preset_bench.hpp"

#include <filesystem>

#include "core/error.hpp"
#include "data/paths/camera_path.hpp"
#include "eval/image_renderer.hpp"
#include "eval/render_setup.hpp"
#include "eval/train_and_evaluate.hpp"
#include "gemm/gemm_tuning.hpp"

namespace mipnerf::bench {
namespace {

train::TrainConfig bench_config(const PresetBenchOptions& options) {
  if (options.warm_steps < 1) throw Error("preset benchmark: at least one warm step is needed");
  auto settings = options.settings;
  const int64_t steps = 1 + options.warm_steps + std::max<int64_t>(0, options.profile_steps);
  settings["steps"] = std::to_string(steps);
  settings["log_every"] = std::to_string(steps);
  settings["checkpoint_every"] = std::to_string(steps);  // one checkpoint, after the last (untimed) step
  settings["keep_checkpoints"] = "1";
  return train::resolve_config(options.preset, train::preset_variant(options.preset), settings);
}

// The run's phases: the first step, timed warm steps, then (optionally) profiled steps.
struct Phases {
  Clock::time_point last;        // end of the previous step (set before step 1)
  Clock::time_point warm_start;  // end of step 1
  int64_t last_step = 0;
  int64_t profiling_from = 0;    // > 0: the profiler was attached after this step
  bool time_box_hit = false;
};

// Hooks that fill `timing` step by step and attach `profiler` once the timed steps are done.
train::TrainHooks timing_hooks(ocl::Context& ctx, const PresetBenchOptions& options, int64_t total,
                               TrainTiming& timing, Phases& phases, ocl::StageProfiler& profiler,
                               const ProgressFn& progress) {
  const bool profile = options.profile_steps > 0;
  train::TrainHooks hooks;
  hooks.on_step = [&, total, profile](const train::StepReport& report) {
    const auto now = Clock::now();
    const double seconds = std::chrono::duration<double>(now - phases.last).count();
    phases.last = now;
    phases.last_step = report.step;
    if (progress) progress("step " + std::to_string(report.step) + "/" + std::to_string(total), report.step, total);
    if (phases.profiling_from > 0) return;
    if (report.step == 1) {
      timing.first_step_seconds = seconds;
      phases.warm_start = now;
      return;
    }
    timing.warm_steps.add(seconds);
    phases.time_box_hit = options.time_box_seconds > 0 && seconds_since(phases.warm_start) >= options.time_box_seconds;
    if (profile && (report.step == 1 + options.warm_steps || phases.time_box_hit)) {
      ctx.set_profiler(&profiler);
      phases.profiling_from = report.step;
    }
  };
  hooks.should_stop = [&, profile] {
    if (phases.profiling_from > 0) return phases.last_step >= phases.profiling_from + options.profile_steps;
    return !profile && phases.time_box_hit;
  };
  return hooks;
}

// What the plan and the device say once the trainer is built.
void record_setup(const train::Trainer& trainer, ocl::Context& ctx, TrainTiming& t) {
  t.parameters = trainer.parameter_count();
  t.batch_rays = static_cast<size_t>(trainer.config().batch_size);
  t.chunk_rays = trainer.memory().chunk_rays;
  t.planned_device_bytes = trainer.memory().total();
  t.memory_budget_bytes = trainer.memory().budget_bytes;
  t.gemm_tuned = gemm::gemm_tuning_installed(ctx);
  t.gemm_backend = enum_name(trainer.networks().front()->backend());
}

RenderTiming time_render(ocl::Context& ctx, train::Trainer& trainer, const PresetBenchOptions& options) {
  RenderTiming timing;
  timing.width = options.render_width;
  timing.height = options.render_height;
  data::ResolutionRequest size;
  size.width = options.render_width;
  size.height = options.render_height;
  const Camera camera = data::resize_camera(trainer.dataset().split("train").cameras.at(0), size);
  timing.chunk_rays =
      eval::render_chunk_rays(trainer.spec(), static_cast<size_t>(trainer.config().render_chunk_rays),
                              ctx.device_info(), 0);
  eval::ImageRenderer renderer(ctx, trainer.spec(), trainer.network_pointers(), trainer.grid_pointers(), {camera},
                               eval::RenderSettings{timing.chunk_rays, 1, 0});
  timing.warm_up_seconds = renderer.warm_up();
  for (size_t r = 0; r < std::max<size_t>(1, options.render_reps); ++r) timing.renders.add(renderer.render(0).seconds);
  if (options.profile_steps > 0 && ctx.profiling_queue()) {  // after the timed renders: events slow it a little
    ocl::StageProfiler profiler;
    ctx.set_profiler(&profiler);
    try {
      profiler.begin_step();
      renderer.render(0);
      profiler.end_step(ctx);
    } catch (...) {
      ctx.set_profiler(nullptr);
      throw;
    }
    ctx.set_profiler(nullptr);
    timing.profile = profiler.profile();
  }
  return timing;
}

}  // namespace

// The host backend keeps the words the committed reports use ("host BLAS"); CLBlast shows its parameters' origin.
std::string TrainTiming::gemm_label() const {
  if (gemm_backend == enum_name(gemm::GemmBackend::clblast)) return gemm_tuned ? "tuned" : "default";
  return gemm_backend == enum_name(gemm::GemmBackend::host) ? "host BLAS" : gemm_backend;
}

std::string TrainTiming::gemm_parameters() const {
  return gemm_backend == enum_name(gemm::GemmBackend::clblast) && !gemm_tuned ? "CLBlast defaults" : gemm_label();
}

PresetBenchResult run_preset_bench(ocl::Context& ctx, const PresetBenchOptions& options, const ProgressFn& progress) {
  PresetBenchResult result;
  result.preset = options.preset;
  result.config = bench_config(options);
  TrainTiming& t = result.train;
  const bool render = options.render_width > 0 && options.render_height > 0;
  Phases phases;
  ocl::StageProfiler profiler;
  if (options.profile_steps > 0 && !ctx.profiling_queue()) {
    throw Error("preset benchmark: profiled steps need a context made with profiling on");
  }
  // The shared train-then-evaluate run, without the val evaluation: the benchmark times a render of its own.
  eval::TrainAndEvaluateOptions run;
  run.data_path = options.data_path;
  run.out_dir = options.work_dir;
  run.evaluate_val = false;
  run.hooks = timing_hooks(ctx, options, result.config.steps, t, phases, profiler, progress);
  t.peak_rss_reset = reset_peak_rss();
  const auto setup_start = Clock::now();
  run.on_setup = [&](train::Trainer& trainer) {
    t.setup_seconds = seconds_since(setup_start);
    record_setup(trainer, ctx, t);
    phases.last = Clock::now();
  };
  run.on_trained = [&](train::Trainer& trainer, const train::TrainResult&) {
    ctx.set_profiler(nullptr);
    t.time_boxed = phases.time_box_hit && static_cast<int64_t>(t.warm_steps.count()) < options.warm_steps;
    if (phases.profiling_from > 0) t.profile = profiler.profile();
    t.peak_rss_bytes = peak_rss_bytes();
    if (!render) return;
    if (progress)
      progress("render", static_cast<size_t>(result.config.steps), static_cast<size_t>(result.config.steps));
    result.render = time_render(ctx, trainer, options);
  };
  try {
    eval::train_and_evaluate(ctx, result.config, run);
  } catch (...) {
    ctx.set_profiler(nullptr);  // the profiler dies with this frame
    throw;
  }
  return result;
}

}  // namespace mipnerf::bench
