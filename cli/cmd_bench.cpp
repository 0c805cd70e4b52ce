// `mipnerf-cl bench`: what each device costs — GEMM GFLOP/s on the MLP's products (CLBlast's defaults and the tuned
// file), every ray-math kernel's throughput, training steps of each preset (rays/s, seconds per step, memory) and
// rendering (seconds per megapixel), cold and warm apart — written as bench.json and bench.md.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <thread>

#include "bench/gemm_bench.hpp"
#include "bench/kernel_bench.hpp"
#include "bench/machine_probe.hpp"
#include "bench/preset_bench.hpp"
#include "bench/report.hpp"
#include "common.hpp"
#include "core/error.hpp"
#include "data/paths/camera_path.hpp"
#include "data/synthetic/procedural.hpp"
#include "eval/render_setup.hpp"
#include "eval/report.hpp"
#include "gemm/clblast_check.hpp"
#include "interrupt.hpp"
#include "io/atomic_file.hpp"
#include "io/temporary_folder.hpp"
#include "progress.hpp"
#include "train/config.hpp"

namespace mipnerf::cli {
namespace fs = std::filesystem;
namespace {

constexpr const char* kSections[] = {"gemm", "kernels", "train"};

struct BenchArgs {
  std::string out = "runs/bench";
  bool quick = false;
  std::vector<std::string> sections = {"gemm", "kernels", "train"};
  std::vector<std::string> presets = {"tiny", "quick", "small", "paper"};
  std::vector<std::string> sets;  // --set name=value over every preset
  std::string data;               // a scene instead of the generated procedural one
  // Defaults of a full run; --quick lowers those not given explicitly (apply_quick).
  int64_t steps = 10;
  int64_t paper_steps = 2;
  double time_box = 120.0;
  int64_t profile_steps = 2;  // per preset, after the timed steps (paper: at most 1)
  size_t gemm_rows = 65536;
  std::vector<size_t> gemm_widths = {64, 128, 256};
  size_t gemm_reps = 5;
  size_t gemm_rounds = 2;
  size_t kernel_rays = 4096;
  size_t kernel_samples = 128;
  size_t kernel_reps = 10;
  std::string render_size = "64x64";
  size_t render_reps = 2;
  uint32_t scene_size = 64;
  uint32_t scene_views = 40;
};

// --quick: the same measurements, smaller and fewer (flags given explicitly win).
void apply_quick(BenchArgs& a, const CLI::App& cmd) {
  if (!a.quick) return;
  auto unset = [&](const char* flag) { return cmd.count(flag) == 0; };
  if (unset("--steps")) a.steps = 3;
  if (unset("--paper-steps")) a.paper_steps = 1;
  if (unset("--time-box")) a.time_box = 30.0;
  if (unset("--gemm-rows")) a.gemm_rows = 16384;
  if (unset("--gemm-widths")) a.gemm_widths = {128, 256};
  if (unset("--gemm-reps")) a.gemm_reps = 3;
  if (unset("--gemm-rounds")) a.gemm_rounds = 1;
  if (unset("--kernel-rays")) a.kernel_rays = 1024;
  if (unset("--kernel-reps")) a.kernel_reps = 3;
  if (unset("--render-size")) a.render_size = "32x32";
  if (unset("--render-reps")) a.render_reps = 1;
  if (unset("--scene-size")) a.scene_size = 32;
  if (unset("--scene-views")) a.scene_views = 16;
}

void check_arguments(const BenchArgs& a) {
  for (const auto& s : a.sections) {
    bool known = false;
    for (const char* name : kSections) known = known || s == name;
    if (!known) throw Error("--sections: unknown section '" + s + "'; the sections are: gemm, kernels, train");
  }
  for (const auto& p : a.presets) {
    if (!train::presets().count(p)) {
      std::string names;
      for (const auto& [name, bundle] : train::presets()) names += (names.empty() ? "" : ", ") + name;
      throw Error("--presets: unknown preset '" + p + "'; the presets are: " + names);
    }
  }
  if (a.steps < 1 || a.paper_steps < 1) throw Error("--steps and --paper-steps must be at least 1 (warm steps)");
  if (a.profile_steps < 0) throw Error("--profile-steps must be >= 0 (0: no stage profile)");
  if (!(a.time_box >= 0)) throw Error("--time-box must be >= 0 seconds (0: no time box)");
  if (a.gemm_rows == 0 || a.gemm_widths.empty() || a.gemm_reps == 0 || a.gemm_rounds == 0) {
    throw Error("--gemm-rows, --gemm-reps and --gemm-rounds must be at least 1, and --gemm-widths non-empty");
  }
  for (size_t w : a.gemm_widths) {
    if (w == 0) throw Error("--gemm-widths: every width must be at least 1");
  }
  if (a.kernel_rays == 0 || a.kernel_samples == 0 || a.kernel_reps == 0) {
    throw Error("--kernel-rays, --kernel-samples and --kernel-reps must be at least 1");
  }
  if (a.scene_size < 1 || a.scene_views < 1) throw Error("--scene-size and --scene-views must be at least 1");
  data::parse_size(a.render_size, "--render-size");
}

bool wants(const BenchArgs& a, const std::string& section) {
  return std::find(a.sections.begin(), a.sections.end(), section) != a.sections.end();
}

// ---- Ctrl-C: the measurement in progress stops, what was measured is written ----

struct Interrupted {};  // thrown from progress callbacks; not a std::exception, so sections do not catch it

// A section's progress line on stderr, drawn from the library's progress callback (which knows the total).
class SectionProgress {
 public:
  explicit SectionProgress(std::string what) : what_(std::move(what)) {}
  bench::ProgressFn callback() {
    return [this](const std::string& detail, size_t done, size_t total) {
      if (StopOnInterrupt::requested()) throw Interrupted{};
      if (!line_) line_ = std::make_unique<Progress>(what_, static_cast<int64_t>(total));
      line_->update(static_cast<int64_t>(done), detail);
    };
  }
  void finish() {
    if (line_) line_->finish();
  }

 private:
  std::string what_;
  std::unique_ptr<Progress> line_;
};

std::string make_scene(const BenchArgs& a, const fs::path& folder) {
  data::SceneOptions options;
  options.size_px = a.scene_size;
  options.train_views = a.scene_views;
  options.val_views = 1;
  options.test_views = 1;
  options.scales = 1;
  std::cerr << "mipnerf-cl: generating the procedural scene (" << a.scene_size << "x" << a.scene_size << ", "
            << a.scene_views << " train views) in " << folder.string() << "\n";
  data::write_procedural_scene(folder.string(), options);
  return folder.string();
}

// ---- one device ----

// A fresh context per section, with CLBlast's compiled programs forgotten: each section's first calls are what a new
// process pays. Info messages only with --verbose (the tuning file is loaded once per section).
std::unique_ptr<ocl::Context> fresh_context(const ocl::DeviceInfo& device, bool profiling = false) {
  bench::clear_clblast_programs();
  auto ctx = std::make_unique<ocl::Context>(device, profiling);
  ctx->set_log([](LogLevel level, const std::string& message) {
    if (level == LogLevel::info && !global_options().verbose) return;
    print_log(level, message);
  });
  return ctx;
}

std::string device_label(const ocl::DeviceInfo& device) { return "[" + std::to_string(device.index) + "] "; }

void bench_gemm(const BenchArgs& a, const ocl::DeviceInfo& device, bench::DeviceBench& d) {
  auto ctx = fresh_context(device);
  std::optional<gemm::GemmTuning> tuning;
  if (d.tuning_found) {
    try {
      tuning = gemm::read_tuning(d.tuning_file);
    } catch (const Error& e) {  // the defaults are still worth measuring
      std::cerr << "mipnerf-cl: warning: " << e.what() << "; GEMM with CLBlast's defaults only\n";
      d.errors.push_back({"gemm tuning file", e.what()});
      d.tuning_found = false;
    }
  }
  bench::GemmBenchOptions options;
  options.widths = a.gemm_widths;
  options.rows = a.gemm_rows;
  options.reps = a.gemm_reps;
  options.rounds = a.gemm_rounds;
  SectionProgress progress(device_label(device) + "gemm");
  auto configs = bench::clblast_configs(tuning);
  if (auto host = bench::host_backend_config(*ctx)) configs.push_back(*host);  // gemm_backend=host beside CLBlast
  d.gemm = bench::run_gemm_bench(*ctx, options, configs, progress.callback());
  progress.finish();
}

void bench_kernels(const BenchArgs& a, const ocl::DeviceInfo& device, bench::DeviceBench& d) {
  auto ctx = fresh_context(device);
  bench::KernelBenchOptions options;
  options.rays = a.kernel_rays;
  options.samples = a.kernel_samples;
  options.reps = a.kernel_reps;
  SectionProgress progress(device_label(device) + "kernels");
  d.kernels = bench::run_kernel_bench(*ctx, options, progress.callback());
  progress.finish();
}

// --set assignments over each preset.
std::map<std::string, std::string> explicit_settings(const BenchArgs& a) {
  return parse_set_assignments(a.sets, "batch_size=256");
}

void bench_preset(const BenchArgs& a, const std::string& preset, const std::string& scene, const fs::path& scratch,
                  const ocl::DeviceInfo& device, bench::DeviceBench& d) {
  auto ctx = fresh_context(device, a.profile_steps > 0);
  bench::PresetBenchOptions options;
  options.preset = preset;
  options.settings = explicit_settings(a);
  options.data_path = scene;
  options.work_dir = (scratch / ("run-" + std::to_string(device.index) + "-" + preset)).string();
  options.warm_steps = preset == "paper" ? a.paper_steps : a.steps;
  options.time_box_seconds = a.time_box;
  options.profile_steps = preset == "paper" ? std::min<int64_t>(1, a.profile_steps) : a.profile_steps;
  const auto [width, height] = data::parse_size(a.render_size, "--render-size");
  options.render_width = width;
  options.render_height = height;
  options.render_reps = a.render_reps;
  SectionProgress progress(device_label(device) + "train " + preset);
  d.presets.push_back(bench::run_preset_bench(*ctx, options, progress.callback()));
  progress.finish();
  std::error_code ec;
  fs::remove_all(options.work_dir, ec);
}

// Runs `section`, recording an error instead of stopping the other measurements.
void run_section(bench::DeviceBench& d, const std::string& section, const std::function<void()>& work) {
  try {
    work();
  } catch (const std::exception& e) {
    std::cerr << "mipnerf-cl: warning: bench " << section << " on " << d.device.value("name", "?")
              << " failed: " << e.what() << "\n";
    d.errors.push_back({section, e.what()});
  }
}

// ---- the record ----

std::string command_line(const CLI::App& cmd) {
  std::string text = "mipnerf-cl";
  if (!global_options().device.empty()) text += " --device " + global_options().device;
  text += " bench";
  for (const CLI::Option* option : cmd.get_options()) {
    if (option->count() == 0 || option->get_name() == "--help") continue;
    text += " " + option->get_name();
    if (option->get_expected_min() == 0) continue;  // a flag
    std::string values;
    for (const auto& v : option->results()) values += (values.empty() ? "" : ",") + v;
    text += " " + values;
  }
  return text;
}

void write_record(const fs::path& out, bench::BenchRun& run, bench::Clock::time_point start) {
  run.seconds = bench::seconds_since(start);
  io::write_bytes_atomically((out / "bench.json").string(), bench::bench_json(run).dump(2) + "\n");
  io::write_bytes_atomically((out / "bench.md").string(), bench::bench_markdown(run));
}

std::vector<ocl::DeviceInfo> devices_to_bench() {
  auto devices = ocl::list_devices();
  if (global_options().device.empty()) return devices;
  return {ocl::choose_device(devices, global_options().device)};
}

void run_bench(BenchArgs& a, const CLI::App& cmd) {
  apply_quick(a, cmd);
  check_arguments(a);
  const auto devices = devices_to_bench();
  const fs::path out = a.out;
  const auto start = bench::Clock::now();

  bench::BenchRun run;
  run.version = MIPNERF_VERSION;
  run.date = eval::utc_timestamp();
  run.command = command_line(cmd);
  run.quick = a.quick;
  run.host = bench::host_record();
  run.presets.warm_steps = a.steps;
  run.presets.paper_warm_steps = a.paper_steps;
  run.presets.time_box_seconds = a.time_box;
  run.presets.render_reps = a.render_reps;
  run.presets.settings = explicit_settings(a);
  for (const auto& preset : a.presets)
    train::resolve_config(preset, train::preset_variant(preset), run.presets.settings);  // bad --set
  // After every argument is checked: a bad one fails at once.
  {
    bench::MachineProbeSettings probe;  // a few seconds: the limits the stage profile's rates are held against
    probe.threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    std::cerr << "mipnerf-cl: bench: probing the machine's limits (FMA peak, memory bandwidth, a large sgemm)\n";
    run.machine = bench::probe_machine(probe);
    std::cerr << "mipnerf-cl: bench: " << bench::machine_summary(run.machine) << "\n";
  }

  io::TemporaryFolder scratch(fs::temp_directory_path(), "mipnerf-cl-bench-");  // scene and runs, removed at the end
  std::string scene = a.data;
  if (wants(a, "train") && !a.presets.empty()) {
    if (scene.empty()) scene = make_scene(a, scratch.path() / "scene");
    run.presets.scene = a.data.empty()
                            ? "the procedural scene (" + std::to_string(a.scene_size) + "x" +
                                  std::to_string(a.scene_size) + ", " + std::to_string(a.scene_views) + " train views)"
                            : a.data;
  }

  try {
    StopOnInterrupt stop;  // the first Ctrl-C ends the section under way; a second one the process
    for (const auto& device : devices) {
      run.devices.emplace_back();
      bench::DeviceBench& d = run.devices.back();
      d.device = eval::device_record(device);
      d.clblast_version = gemm::clblast_version();
      d.tuning_file = gemm::tuning_file_path(device);
      d.tuning_found = fs::exists(d.tuning_file);
      std::cerr << "mipnerf-cl: benchmarking " << device_label(device) << device.name << " (" << device.platform_name
                << "); GEMM tuning: " << (d.tuning_found ? d.tuning_file : "none (CLBlast's defaults only)") << "\n";
      if (wants(a, "gemm")) run_section(d, "gemm", [&] { bench_gemm(a, device, d); });
      write_record(out, run, start);
      if (wants(a, "kernels")) run_section(d, "kernels", [&] { bench_kernels(a, device, d); });
      write_record(out, run, start);
      if (!wants(a, "train")) continue;
      for (const auto& preset : a.presets) {
        run_section(d, "train " + preset, [&] { bench_preset(a, preset, scene, scratch.path(), device, d); });
        write_record(out, run, start);
      }
    }
  } catch (const Interrupted&) {
    run.host_at_end = bench::host_record();
    write_record(out, run, start);
    throw Error("interrupted: what was measured so far is in " + (out / "bench.md").string() + " and bench.json");
  }
  run.complete = true;
  run.host_at_end = bench::host_record();
  write_record(out, run, start);
  std::printf("%s", bench::bench_markdown(run).c_str());
  std::printf("benchmarked %zu device(s) in %s; results in %s and %s\n", devices.size(),
              format_duration(run.seconds).c_str(), (out / "bench.json").string().c_str(),
              (out / "bench.md").string().c_str());
}

}  // namespace

void register_bench(CLI::App& app) {
  auto args = std::make_shared<BenchArgs>();
  auto* cmd = app.add_subcommand(
      "bench",
      "Measure every OpenCL device (or the one --device picks): GEMM GFLOP/s on the MLP's products with CLBlast's "
      "default and tuned parameters, each ray-math kernel's throughput, training steps of each preset (rays/s, "
      "s/step, memory) and render s/MP, first (cold) calls apart; writes bench.json and bench.md. On 2 CPU cores "
      "(PoCL) a full run takes about 10 minutes, --quick about 4 (the paper preset's steps take most of it)");
  cmd->add_option("--out", args->out, "Output folder for bench.json and bench.md (overwritten)")->capture_default_str();
  cmd->add_flag("--quick", args->quick,
                "Smaller and fewer measurements: 3 warm steps (paper 1), 30 s time box, GEMM 16384 rows widths "
                "128,256 one round of 3, kernels 1024 rays 3 calls, 32x32 scene and renders (explicit flags win)");
  cmd->add_option("--sections", args->sections, "What to measure: gemm, kernels, train (training and rendering)")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--presets", args->presets, "Training presets to measure, in order")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--set", args->sets, "A training setting over every preset, name=value (repeatable)");
  cmd->add_option("--data", args->data, "Train on this scene instead of the generated procedural one");
  cmd->add_option("--steps", args->steps, "Warm training steps per CPU preset (after the first, cold one)")
      ->capture_default_str();
  cmd->add_option("--paper-steps", args->paper_steps, "Warm steps of the paper preset (minutes each on a CPU)")
      ->capture_default_str();
  cmd->add_option("--time-box", args->time_box,
                  "Per preset: no new warm step after this many seconds of them (at least one; 0: none)")
      ->capture_default_str();
  cmd->add_option("--profile-steps", args->profile_steps,
                  "Per preset, steps profiled by stage after the timed ones (paper: at most 1; 0: none)")
      ->capture_default_str();
  cmd->add_option("--gemm-rows", args->gemm_rows, "Rows (samples) of the GEMM products")->capture_default_str();
  cmd->add_option("--gemm-widths", args->gemm_widths, "Layer widths of the GEMM products")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--gemm-reps", args->gemm_reps, "Timed calls per product and round")->capture_default_str();
  cmd->add_option("--gemm-rounds", args->gemm_rounds, "Rounds over the configurations")->capture_default_str();
  cmd->add_option("--kernel-rays", args->kernel_rays, "Rays of the kernel batch")->capture_default_str();
  cmd->add_option("--kernel-samples", args->kernel_samples, "Samples per ray of the kernel batch")
      ->capture_default_str();
  cmd->add_option("--kernel-reps", args->kernel_reps, "Timed calls per kernel")->capture_default_str();
  cmd->add_option("--render-size", args->render_size, "Rendered image size, WxH")->capture_default_str();
  cmd->add_option("--render-reps", args->render_reps, "Timed renders per preset")->capture_default_str();
  cmd->add_option("--scene-size", args->scene_size, "Procedural scene image size (pixels)")->capture_default_str();
  cmd->add_option("--scene-views", args->scene_views, "Procedural scene training views")->capture_default_str();
  cmd->callback([args, cmd] { run_bench(*args, *cmd); });
}

}  // namespace mipnerf::cli
