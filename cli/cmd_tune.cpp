// `mipnerf-cl tune`: measures CLBlast GEMM parameters for this device on the MLP's own products and stores the
// best in the per-device file every later run loads (host/mlp/gemm_tuning.hpp).
//
// The search itself (what to try, scoring, the winners, the report) is gemm::GemmTuner (host/mlp/gemm_tuner.hpp).
// This file holds the flags, the printing, and how each step runs: in a child process (this executable's
// hidden `__tune-step` subcommand), because CLBlast's tuners compile hundreds of kernel variants and a driver
// can crash on one (PoCL does, e.g. TuneTranspose on a non-square matrix), which then costs that step only.
// The parent never runs OpenCL work; it starts each step with a deadline (killing it when it overruns or on
// Ctrl-C) and shows the progress of the time box while it runs.
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <thread>

#include "bench/backend_tuning.hpp"
#include "common.hpp"
#include "core/error.hpp"
#include "gemm/clblast_check.hpp"
#include "gemm/gemm_backend.hpp"
#include "gemm/gemm_tune_steps.hpp"
#include "gemm/gemm_tuner.hpp"
#include "gemm/gemm_tuning.hpp"
#include "gemm/host_library_tuner.hpp"
#include "interrupt.hpp"
#include "io/atomic_file.hpp"
#include "io/json.hpp"
#include "io/temporary_folder.hpp"
#include "mlp/mlp_products.hpp"
#include "progress.hpp"

namespace mipnerf::cli {
namespace {

using Clock = std::chrono::steady_clock;

struct TuneArgs {
  gemm::GemmTuneSettings settings;
  size_t input_width = 96;  // the network tuned for: its input features, view branch, view dependence
  size_t view_branch_width = 128;
  bool no_view = false;
  std::string output;           // default: the per-device file
  bool if_missing = false;      // do nothing when the per-device file already exists (quick start re-runs)
  bool host_gemm_only = false;  // only the host step: the CPU GEMM library per product (gemm/host_library_tuner.hpp)
  std::vector<std::string> host_gemm_presets{"tiny", "quick", "small", "paper"};  // whose networks' products
  int host_gemm_rounds = 5;  // timed batches per product and library (the median decides)
};

struct StepArgs {
  std::string spec;
  std::string result;
};

// The whole file; "" when it is missing (a step that died before writing its log).
std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// ==== the child: one step on the device ====

void run_step(const StepArgs& args) {
  const io::Json spec = io::parse_json(read_text(args.spec), args.spec);
  auto ctx = open_context();
  // The step's messages go to its stderr as they are: the parent shows the last line when the step fails.
  const LogFn to_stderr = [](LogLevel, const std::string& message) { std::cerr << message << "\n"; };
  const io::Json result = gemm::run_tune_step(*ctx, spec, to_stderr);
  io::write_bytes_atomically(args.result, result.dump());
}

// ==== the parent: deadlines, interrupts, progress ====

std::string self_path() {
  char buffer[4096];
  const ssize_t n = ::readlink("/proc/self/exe", buffer, sizeof(buffer) - 1);
  if (n <= 0) throw Error("cannot find this executable (/proc/self/exe) to start the tuning steps");
  return std::string(buffer, static_cast<size_t>(n));
}

// A finished line above the progress line (which redraws itself below it).
void note(const std::string& message) {
  std::cerr << (isatty(STDERR_FILENO) ? "\r\033[K" : "") << "mipnerf-cl: tune: " << message << "\n";
}

// "crashed (signal 11)", "failed (exit 1)", or "" for a clean exit.
std::string exit_problem(int status) {
  if (WIFSIGNALED(status)) return "crashed (signal " + std::to_string(WTERMSIG(status)) + ")";
  if (WIFEXITED(status) && WEXITSTATUS(status) != 0) return "failed (exit " + std::to_string(WEXITSTATUS(status)) + ")";
  return "";
}

// Runs each step as `mipnerf-cl --device <i> __tune-step --spec <file> --result <file>` in a folder of its own
// under /tmp (removed at the end), its output going to a log file there.
class ChildStepRunner {
 public:
  ChildStepRunner(const ocl::DeviceInfo& device, double minutes)
      : exe_(self_path()),
        device_index_(device.index),
        time_box_s_(minutes * 60.0),
        start_(Clock::now()),
        progress_("tune", static_cast<int64_t>(minutes * 60.0)),
        work_("/tmp", "mipnerf-tune-") {}
  ~ChildStepRunner() {
    std::error_code error;
    work_.remove(error);
    if (error) std::cerr << "mipnerf-cl: could not remove " << work_.path().string() << "\n";
  }
  ChildStepRunner(const ChildStepRunner&) = delete;
  ChildStepRunner& operator=(const ChildStepRunner&) = delete;

  void finish_progress() { progress_.finish("done"); }

  // Runs one step in a child with a deadline, showing the overall progress while it runs.
  gemm::TuneStepOutcome run(const std::string& name, const io::Json& spec, double timeout_s) {
    gemm::TuneStepOutcome outcome;
    if (StopOnInterrupt::requested()) {
      outcome.status = "interrupted";
      return outcome;
    }
    const std::string id = std::to_string(step_count_++);
    const std::string spec_path = in_work("step" + id + ".json"), result_path = in_work("result" + id + ".json");
    const std::string log_path = in_work("step" + id + ".log");
    io::write_bytes_atomically(spec_path, spec.dump());
    const auto started = Clock::now();
    const pid_t pid = start_child(spec_path, result_path, log_path);
    int status = 0;
    const bool timed_out = wait_for(pid, name, started, timeout_s, status);
    outcome.seconds = std::chrono::duration<double>(Clock::now() - started).count();
    if (StopOnInterrupt::requested()) {
      outcome.status = "interrupted";
    } else if (timed_out) {
      outcome.status = "timed out after " + format_duration(timeout_s);
    } else if (const std::string problem = exit_problem(status); !problem.empty()) {
      outcome.status = problem;
    } else {
      read_result(result_path, outcome);
    }
    if (!outcome.ok && outcome.status != "interrupted") tell_failure(name, outcome.status, log_path);
    return outcome;
  }

 private:
  std::string in_work(const std::string& name) const { return (work_.path() / name).string(); }

  pid_t start_child(const std::string& spec_path, const std::string& result_path, const std::string& log_path) {
    std::vector<std::string> argv_text = {
        exe_, "--device", std::to_string(device_index_), "__tune-step", "--spec", spec_path, "--result", result_path};
    // Everything the child needs is prepared before fork(): between fork and exec only async-signal-safe
    // calls (the OpenCL runtime may have started threads in this process).
    std::vector<char*> argv;
    for (auto& a : argv_text) argv.push_back(a.data());
    argv.push_back(nullptr);
    const int log_fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (log_fd < 0) throw Error("cannot create " + log_path);
    const pid_t pid = ::fork();
    if (pid < 0) throw Error("fork failed: cannot start a tuning step");
    if (pid == 0) {
      // The child: its messages go to the step's log (the parent keeps the terminal for the progress line).
      ::dup2(log_fd, STDERR_FILENO);
      ::dup2(log_fd, STDOUT_FILENO);
      ::execv(argv[0], argv.data());
      _exit(127);
    }
    ::close(log_fd);
    return pid;
  }

  // Waits for the child, killing it past its deadline or on Ctrl-C. Returns whether the deadline killed it.
  bool wait_for(pid_t pid, const std::string& name, Clock::time_point started, double timeout_s, int& status) {
    while (true) {
      if (::waitpid(pid, &status, WNOHANG) == pid) return false;
      const double running = std::chrono::duration<double>(Clock::now() - started).count();
      if (running > timeout_s || StopOnInterrupt::requested()) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
        return !StopOnInterrupt::requested();
      }
      const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
      progress_.update(static_cast<int64_t>(std::min(elapsed, time_box_s_)),
                       name + " (" + format_duration(running) + " of at most " + format_duration(timeout_s) + ")");
      std::this_thread::sleep_for(std::chrono::milliseconds(250));
    }
  }

  static void read_result(const std::string& result_path, gemm::TuneStepOutcome& outcome) {
    try {
      outcome.result = io::Json::parse(read_text(result_path));
      outcome.ok = true;
      outcome.status = "ok";
    } catch (const std::exception&) {
      outcome.status = "failed (no result)";
    }
  }

  // The step's name, what went wrong, and the last line it wrote (usually the error).
  static void tell_failure(const std::string& name, const std::string& status, const std::string& log_path) {
    const std::string log = read_text(log_path);
    const auto last_line = log.find_last_of('\n', log.size() >= 2 ? log.size() - 2 : 0);
    note(name + " " + status +
         (log.empty() ? "" : ": " + log.substr(last_line == std::string::npos ? 0 : last_line + 1)));
  }

  std::string exe_;
  size_t device_index_;
  double time_box_s_;
  Clock::time_point start_;
  Progress progress_;
  io::TemporaryFolder work_;  // the steps' specs, results and logs
  int step_count_ = 0;
};

void print_summary(const gemm::GemmTuner& tuner, const ocl::DeviceInfo& device, size_t rows) {
  std::cout << "GEMM parameters for " << device.name << " (" << gemm::clblast_version() << "), time per step of "
            << "the MLP's products at " << rows << " rows:\n";
  for (const auto& winner : tuner.winners()) {
    std::printf("  %-17s %8.3f s  %s", gemm::gemm_kind_name(winner.kind), winner.seconds, winner.candidate.c_str());
    if (winner.default_seconds && *winner.default_seconds > 0) {
      std::printf("  (CLBlast defaults %.3f s: %.2fx faster)", *winner.default_seconds,
                  *winner.default_seconds / winner.seconds);
    }
    std::printf("\n");
  }
  std::cout << "written to " << tuner.output_path() << "\n";
}

void check_args(const TuneArgs& args) {
  const gemm::GemmTuneSettings& s = args.settings;
  if (s.minutes <= 0) throw Error("--minutes must be positive");
  if (s.rows % 64 != 0 || s.kernel_rows % 128 != 0 || s.rows == 0 || s.kernel_rows == 0) {
    throw Error("--rows must be a multiple of 64 and --kernel-rows of 128 (CLBlast's tuners need whole tiles)");
  }
  if (s.width % 128 != 0) throw Error("--width must be a multiple of 128 for CLBlast's Xgemm tuner");
}

// The network `tune` tunes for, from its flags (the bottleneck as wide as the trunk, as the presets have it).
mlp::MlpConfig tuned_network(const TuneArgs& args) {
  mlp::MlpConfig config;
  config.width = args.settings.width;
  config.input_width = args.input_width;
  config.view_branch_width = args.view_branch_width;
  config.bottleneck_width = args.settings.width;
  config.view_dependence = !args.no_view;
  return config;
}

// After the parameter search: which backend gemm_backend=auto takes on this device (bench/backend_tuning.hpp).
void measure_backends(const ocl::DeviceInfo& device, const std::string& path, const TuneArgs& args) {
  const auto measured = bench::measure_auto_backend(device, path, tuned_network(args), args.settings.rows);
  if (!measured) return;
  std::printf("gemm_backend=auto on this device: %s (whole network, %zu rows, forward + backward:",
              enum_name(measured->fastest), measured->rows);
  for (const auto& [backend, seconds] : measured->seconds) std::printf(" %s %.3f s", enum_name(backend), seconds);
  std::printf(")\n");
}

// The host step: the CPU GEMM library per product of the host MLP (gemm/host_library_tuner.hpp), with a table as it
// goes. Says why and does nothing where the host backend cannot run.
void tune_host_libraries(const ocl::DeviceInfo& device, const std::string& path, const TuneArgs& args) {
  try {
    gemm::check_host_libraries_can_run(device);
  } catch (const Error& e) {
    std::cerr << "mipnerf-cl: tune: no host GEMM libraries to choose between: " << e.what() << "\n";
    return;
  }
  for (const auto& line : gemm::cpu_sgemm_libraries_left_out()) std::cerr << "mipnerf-cl: tune: " << line << "\n";
  const auto settings = gemm::host_library_timing_settings(device, args.host_gemm_rounds);
  const auto products = bench::host_products_to_tune(tuned_network(args), args.host_gemm_presets);
  std::cerr << "mipnerf-cl: tune: the host MLP's products, " << products.size() << " shapes x "
            << gemm::cpu_sgemm_libraries().size() << " libraries, " << settings.threads
            << " threads each on its own block (GFLOP/s, median of " << settings.rounds << "):\n";
  gemm::tune_host_libraries(device, path, products, settings, [](const gemm::HostProductChoice& choice) {
    std::fprintf(stderr, "  %-34s", choice.label.c_str());
    for (const auto& [library, t] : choice.timings) {
      if (t.skipped.empty()) {
        std::fprintf(stderr, " %s %.0f", library.c_str(), t.gflops_median);
      } else {
        std::fprintf(stderr, " %s -", library.c_str());
      }
    }
    std::fprintf(stderr, "  -> %s\n", choice.chosen.c_str());
  });
  std::cerr << "mipnerf-cl: tune: the host MLP's library per product is in " << path << "\n";
}

void run_tune(const TuneArgs& args) {
  if (!args.host_gemm_only) check_args(args);  // CLBlast's constraints; the host step times any width
  const auto devices = ocl::list_devices();
  const ocl::DeviceInfo device = ocl::choose_device(devices, global_options().device);
  const std::string path = args.output.empty() ? gemm::tuning_file_path(device) : args.output;
  if (args.host_gemm_only) {
    if (args.if_missing) {
      const std::optional<gemm::GemmTuning> existing = gemm::read_tuning(path);
      if (existing && gemm::tuning_matches(*existing, device) && !existing->host_libraries.empty()) {
        std::cerr << "mipnerf-cl: tune: " << path << " already chooses the host MLP's libraries; nothing to do "
                  << "(--if-missing)\n";
        return;
      }
    }
    tune_host_libraries(device, path, args);
    return;
  }
  if (args.if_missing && std::filesystem::exists(path)) {
    std::cerr << "mipnerf-cl: tune: " << path << " exists; nothing to do (--if-missing)\n";
    return;
  }
  // CLBlast's parameters only matter where CLBlast runs the products: with gemm_backend=auto a CPU device that
  // shares host memory uses the host BLAS instead, so the quick start need not spend minutes tuning it.
  if (args.if_missing && gemm::resolve_gemm_backend(gemm::GemmBackend::automatic, device,
                                                    gemm::host_blas_available()) == gemm::GemmBackend::host) {
    std::cerr << "mipnerf-cl: tune: not needed: on " << device.name
              << " the MLP's products run on the host BLAS (gemm_backend=auto); tuning matters with "
                 "gemm_backend=clblast (run tune without --if-missing)\n";
    return;
  }
  gemm::GemmTuneSettings settings = args.settings;
  settings.problems = mlp::mlp_gemm_problems(tuned_network(args), settings.rows);
  ChildStepRunner runner(device, settings.minutes);
  gemm::GemmTuner tuner(
      settings, device, path,
      [&runner](const std::string& name, const io::Json& spec, double timeout_s) {
        return runner.run(name, spec, timeout_s);
      },
      [](LogLevel, const std::string& message) { note(message); }, [] { return StopOnInterrupt::requested(); });
  StopOnInterrupt stop;  // Ctrl-C or SIGTERM: the step under way is killed, the best parameters so far are kept
  std::cerr << "mipnerf-cl: tune: " << device.name << ", CLBlast " << gemm::clblast_version() << ", time box "
            << format_duration(settings.minutes * 60.0) << "; every step runs in its own process; results go to "
            << path << "\n";
  tuner.run();
  runner.finish_progress();
  print_summary(tuner, device, settings.rows);
  if (StopOnInterrupt::requested()) throw Error("tune interrupted; the best parameters found so far are in " + path);
  measure_backends(device, path, args);
  tune_host_libraries(device, path, args);
}

}  // namespace

void register_tune(CLI::App& app) {
  auto args = std::make_shared<TuneArgs>();
  auto* cmd =
      app.add_subcommand("tune",
                         "Measure CLBlast GEMM parameters for this device on the MLP's products and store the best "
                         "(loaded automatically by later runs)");
  cmd->add_option("--minutes", args->settings.minutes, "Time box for the whole tune")->capture_default_str();
  cmd->add_option("--rows", args->settings.rows, "Rows (samples) of the products timed through CLBlast's routine")
      ->capture_default_str();
  cmd->add_option("--kernel-rows", args->settings.kernel_rows, "Rows of the kernel-level tuners (multiple of 128)")
      ->capture_default_str();
  cmd->add_option("--width", args->settings.width, "MLP width W")->capture_default_str();
  cmd->add_option("--input-width", args->input_width, "MLP input features (IPE: 96, NeRF PE: 63)")
      ->capture_default_str();
  cmd->add_option("--view-branch-width", args->view_branch_width, "Width of the view branch")->capture_default_str();
  cmd->add_flag("--no-view", args->no_view, "The MLP has no view branch");
  cmd->add_option("--output", args->output, "Write the parameters here instead of the per-device cache file");
  cmd->add_flag("--if-missing", args->if_missing, "Do nothing when the tuning file already exists");
  cmd->add_flag("--host-gemm", args->host_gemm_only,
                "Only choose the CPU GEMM library (OpenBLAS, BLIS, oneDNN, libxsmm: those built in) for each of the "
                "host MLP's products on this CPU device, by timing them (about a minute; no CLBlast search)");
  cmd->add_option("--host-gemm-presets", args->host_gemm_presets,
                  "Presets whose networks' products the host step times (besides the network of --width etc.)")
      ->capture_default_str();
  cmd->add_option("--host-gemm-rounds", args->host_gemm_rounds,
                  "Timed batches per product and library in the host step; the median decides")
      ->capture_default_str()
      ->check(CLI::Range(1, 50));
  cmd->callback([args] { run_tune(*args); });

  // The child side: one step, started by `tune` itself (hidden from --help).
  auto step = std::make_shared<StepArgs>();
  auto* hidden = app.add_subcommand("__tune-step", "");
  hidden->group("");
  hidden->add_option("--spec", step->spec)->required();
  hidden->add_option("--result", step->result)->required();
  hidden->callback([step] { run_step(*step); });
}

}  // namespace mipnerf::cli
