// What a training preset costs on a device: seconds per training step (the first apart: it builds the kernels and
// CLBlast's programs), rays per second, the memory it plans on the device and the process's peak RSS, then the
// render time per megapixel of its networks. Shared by `mipnerf-cl bench` and the tests.
//
// A preset is trained for 1 + warm_steps (+ profile_steps) steps (fewer when the time box runs out, never fewer than one warm step)
// through the real train::Trainer, on whatever scene data_path holds (the CLI generates the procedural scene). The
// step time is the wall time between the trainer's step reports (batch sampling, every chunk's forward and
// backward, Adam); checkpoints are written only after the last step, outside the timing. The render measurement
// renders one camera of the training split, resized, through eval::ImageRenderer with the trained networks:
// first its warm-up chunk (what the inference graph builds that training did not), then timed renders.
// Profiled steps (StageProfiler, cl/profiler.hpp) follow the timed ones and are left out of their timing: profiling
// waits for the queue at the end of each step and records an event per command.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "bench/timing.hpp"
#include "cl/context.hpp"
#include "train/config.hpp"

namespace mipnerf::bench {

struct PresetBenchOptions {
  std::string preset = "tiny";                   // a name of train::presets()
  std::map<std::string, std::string> settings;   // over the preset (e.g. a smaller batch in tests)
  std::string data_path;                         // the scene to train on
  std::string work_dir;                          // the run's checkpoint and log (created; the caller removes it)
  int64_t warm_steps = 10;                       // timed steps after the first
  double time_box_seconds = 0.0;                 // > 0: no new warm step starts after this many seconds of them
  int64_t profile_steps = 0;                     // > 0: this many more steps, profiled by stage (needs a context
                                                 // made with profiling on); never counted in the timing
  uint32_t render_width = 64;                    // render measurement size; 0 skips it
  uint32_t render_height = 64;
  size_t render_reps = 1;                        // timed renders after the warm-up
};

struct TrainTiming {
  size_t parameters = 0;
  size_t batch_rays = 0;                 // rays per step
  size_t chunk_rays = 0;                 // rays per chunk, as planned for the device
  size_t planned_device_bytes = 0;       // train::Trainer::memory().total(): graph, dataset, networks, Adam
  size_t memory_budget_bytes = 0;        // what the plan allowed itself of the device's memory
  bool gemm_tuned = false;               // tuned CLBlast parameters were installed while it trained
  std::string gemm_backend = "clblast";  // the backend that ran the products (gemm::GemmBackend's name, never auto)
  // What ran the products, as the report's table shows it: CLBlast's parameters ("tuned" or "default"), "host BLAS",
  // or another backend's name.
  std::string gemm_label() const;
  // The same in the report's JSON ("CLBlast defaults" for CLBlast's own parameters).
  std::string gemm_parameters() const;
  double setup_seconds = 0.0;            // Trainer construction: data load and upload, buffers, graph programs
  double first_step_seconds = 0.0;      // step 1: first kernel launches and CLBlast's program builds included
  Timings warm_steps;                    // steps 2 …, seconds each
  bool time_boxed = false;               // the time box ended the warm steps before warm_steps
  size_t peak_rss_bytes = 0;             // the process's peak RSS over setup and steps (see peak_rss_reset)
  bool peak_rss_reset = false;           // true: the peak was reset before setup (else: since the process began)
  std::optional<ocl::StageProfile> profile;  // the profiled steps after the timed ones (profile_steps > 0)
  double rays_per_second() const {       // from the median warm step
    return warm_steps.median() > 0 ? static_cast<double>(batch_rays) / warm_steps.median() : 0.0;
  }
};

struct RenderTiming {
  uint32_t width = 0, height = 0;
  size_t chunk_rays = 0;
  double warm_up_seconds = 0.0;  // the first chunk: programs the inference graph needs beyond training's
  Timings renders;               // whole-image renders after it, seconds each
  // One more render with the stage profiler attached (when the preset's steps are profiled): where it spent its
  // time, the image as one profiled "step" of width × height rays.
  std::optional<ocl::StageProfile> profile;
  double megapixels() const { return static_cast<double>(width) * height / 1e6; }
  double seconds_per_megapixel() const { return renders.best() / megapixels(); }  // from the best render
};

struct PresetBenchResult {
  std::string preset;
  train::TrainConfig config;  // as trained (preset, then options.settings, then the step counts)
  TrainTiming train;
  std::optional<RenderTiming> render;
};

// `progress` is called after every step ("step k/n") and before the render. Throws mipnerf::Error for an unknown
// preset or setting, data that does not load, or a configuration that does not fit the device.
PresetBenchResult run_preset_bench(ocl::Context& ctx, const PresetBenchOptions& options,
                                   const ProgressFn& progress = {});

}  // namespace mipnerf::bench
