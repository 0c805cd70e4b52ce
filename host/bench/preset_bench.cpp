// Training steps and a render of one preset, timed through the real trainer and renderer (see preset_bench.hpp).
#include "bench/preset_bench.hpp"

#include <filesystem>

#include "core/error.hpp"
#include "data/camera_path.hpp"
#include "eval/image_renderer.hpp"
#include "mlp/gemm_tuning.hpp"
#include "train/memory_plan.hpp"
#include "train/trainer.hpp"

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

// Trains and fills `timing` step by step.
void time_training(train::Trainer& trainer, const PresetBenchOptions& options, TrainTiming& timing,
                   const ProgressFn& progress) {
  const int64_t total = trainer.config().steps;
  auto last = Clock::now();
  Clock::time_point warm_start;
  train::TrainHooks hooks;
  hooks.on_step = [&](const train::StepReport& report) {
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
  last = Clock::now();
  const train::TrainResult result = trainer.run(hooks);
  timing.time_boxed = result.interrupted;
}

RenderTiming time_render(ocl::Context& ctx, train::Trainer& trainer, const PresetBenchOptions& options) {
  RenderTiming timing;
  timing.width = options.render_width;
  timing.height = options.render_height;
  data::ResolutionRequest size;
  size.width = options.render_width;
  size.height = options.render_height;
  const Camera camera = data::resize_camera(trainer.dataset().split("train").cameras.at(0), size);
  const size_t network_bytes = trainer.parameter_count() * sizeof(float);
  const auto plan = train::plan_memory(trainer.spec(), ctx.device_info(),
                                       static_cast<size_t>(trainer.config().render_chunk_rays), network_bytes, 0, false);
  timing.chunk_rays = plan.chunk_rays;
  std::vector<mlp::Mlp*> networks;
  for (auto& n : trainer.networks()) networks.push_back(n.get());
  eval::ImageRenderer renderer(ctx, trainer.spec(), networks, {camera}, eval::RenderSettings{plan.chunk_rays, 1, 0});
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
  t.peak_rss_reset = reset_peak_rss();
  const auto setup_start = Clock::now();
  train::Trainer trainer(ctx, result.config, options.data_path, options.work_dir, false);
  t.setup_seconds = seconds_since(setup_start);
  t.parameters = trainer.parameter_count();
  t.batch_rays = static_cast<size_t>(result.config.batch_size);
  t.chunk_rays = trainer.memory().chunk_rays;
  t.planned_device_bytes = trainer.memory().total();
  t.memory_budget_bytes = trainer.memory().budget_bytes;
  t.gemm_tuned = mlp::gemm_tuning_installed(ctx);
  time_training(trainer, options, t, progress);
  t.peak_rss_bytes = peak_rss_bytes();
  if (options.render_width > 0 && options.render_height > 0) {
    if (progress) progress("render", static_cast<size_t>(result.config.steps), static_cast<size_t>(result.config.steps));
    result.render = time_render(ctx, trainer, options);
  }
  return result;
}

}  // namespace mipnerf::bench
