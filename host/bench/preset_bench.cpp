// Training steps and a render of one preset, timed through the real trainer and renderer (see preset_bench.hpp).
#include "bench/preset_bench.hpp"

#include <filesystem>

#include "core/error.hpp"
#include "data/camera_path.hpp"
#include "eval/image_renderer.hpp"
#include "eval/render_setup.hpp"
#include "eval/train_and_evaluate.hpp"
#include "mlp/gemm_tuning.hpp"

namespace mipnerf::bench {
namespace {

train::TrainConfig bench_config(const PresetBenchOptions& options) {
  if (options.warm_steps < 1) throw Error("preset benchmark: at least one warm step is needed");
  auto settings = options.settings;
  const int64_t steps = 1 + options.warm_steps;
  settings["steps"] = std::to_string(steps);
  settings["log_every"] = std::to_string(steps);
  settings["checkpoint_every"] = std::to_string(steps);  // one checkpoint, after the last (untimed) step
  settings["keep_checkpoints"] = "1";
  return train::resolve_config(options.preset, "mipnerf", settings);
}

// Hooks that fill `timing` step by step; `last` is the end of the previous step (set before step 1).
train::TrainHooks timing_hooks(const PresetBenchOptions& options, int64_t total, TrainTiming& timing,
                               Clock::time_point& last, Clock::time_point& warm_start, const ProgressFn& progress) {
  train::TrainHooks hooks;
  hooks.on_step = [&, total](const train::StepReport& report) {
    const auto now = Clock::now();
    const double seconds = std::chrono::duration<double>(now - last).count();
    last = now;
    if (report.step == 1) {
      timing.first_step_seconds = seconds;
      warm_start = now;
    } else {
      timing.warm_steps.add(seconds);
    }
    if (progress) progress("step " + std::to_string(report.step) + "/" + std::to_string(total), report.step, total);
  };
  hooks.should_stop = [&] {
    if (options.time_box_seconds <= 0 || timing.warm_steps.empty()) return false;
    return seconds_since(warm_start) >= options.time_box_seconds;
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
  t.gemm_tuned = mlp::gemm_tuning_installed(ctx);
  t.gemm_on_host = ctx.gemm_on_host();  // the trainer has applied gemm_backend by now
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
      eval::render_chunk_rays(trainer.spec(), trainer.parameter_count(),
                              static_cast<size_t>(trainer.config().render_chunk_rays), ctx.device_info(), 0);
  eval::ImageRenderer renderer(ctx, trainer.spec(), trainer.network_pointers(), {camera},
                               eval::RenderSettings{timing.chunk_rays, 1, 0});
  timing.warm_up_seconds = renderer.warm_up();
  for (size_t r = 0; r < std::max<size_t>(1, options.render_reps); ++r) timing.renders.add(renderer.render(0).seconds);
  return timing;
}

}  // namespace

PresetBenchResult run_preset_bench(ocl::Context& ctx, const PresetBenchOptions& options, const ProgressFn& progress) {
  PresetBenchResult result;
  result.preset = options.preset;
  result.config = bench_config(options);
  TrainTiming& t = result.train;
  const bool render = options.render_width > 0 && options.render_height > 0;
  Clock::time_point last, warm_start;
  // The shared train-then-evaluate run, without the val evaluation: the benchmark times a render of its own.
  eval::TrainAndEvaluateOptions run;
  run.data_path = options.data_path;
  run.out_dir = options.work_dir;
  run.evaluate_val = false;
  run.hooks = timing_hooks(options, result.config.steps, t, last, warm_start, progress);
  t.peak_rss_reset = reset_peak_rss();
  const auto setup_start = Clock::now();
  run.on_setup = [&](train::Trainer& trainer) {
    t.setup_seconds = seconds_since(setup_start);
    record_setup(trainer, ctx, t);
    last = Clock::now();
  };
  run.on_trained = [&](train::Trainer& trainer, const train::TrainResult& trained) {
    t.time_boxed = trained.interrupted;
    t.peak_rss_bytes = peak_rss_bytes();
    if (!render) return;
    if (progress)
      progress("render", static_cast<size_t>(result.config.steps), static_cast<size_t>(result.config.steps));
    result.render = time_render(ctx, trainer, options);
  };
  eval::train_and_evaluate(ctx, result.config, run);
  return result;
}

}  // namespace mipnerf::bench
