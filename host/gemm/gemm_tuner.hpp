// The search behind `mipnerf-cl tune`: which CLBlast GEMM parameters to try (CLBlast's defaults, hand-picked
// starting sets, its own kernel tuners), how each candidate is scored on the MLP's real products, and which
// set wins per product kind; the winners go to the per-device tuning file (mlp/gemm_tuning.hpp).
//
// The tuner never touches the device itself. Each piece of device work is a "step" described as JSON and
// handed to a TuneStepRunner, which runs it (mlp/gemm_tune_steps.hpp does the work) and says how it went.
// The CLI runs every step in a child process with a deadline, because a driver can crash on one of the
// hundreds of kernel variants CLBlast's tuners compile; tests run steps in-process or fake their results.
// The tuner rewrites the tuning file after every improvement, so an interrupted tune keeps its best.
#pragma once

#include <chrono>
#include <cstddef>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cl/context.hpp"
#include "core/log.hpp"
#include "io/json.hpp"
#include "gemm/gemm_tune_steps.hpp"
#include "gemm/gemm_tuning.hpp"

namespace mipnerf::gemm {

// The products to tune for and the time box (the flags of `mipnerf-cl tune`).
struct GemmTuneSettings {
  double minutes = 30.0;      // the time box
  size_t rows = 65536;        // rows of the products timed through the routine
  size_t kernel_rows = 4096;  // rows of the kernel-level tuners (same tiles, shorter runs)
  size_t width = 256;         // the width of the matrices the helper kernels move and of the crossover's products
  // The products of one training step at `rows` rows, with their counts (mlp::mlp_gemm_problems of the network):
  // what the candidates are timed on. Must not be empty.
  std::vector<GemmProblem> problems;
};

// How one step went. `status` is "ok", "interrupted", "timed out after 5m00s", "crashed (signal 11)",
// "failed (exit 1)" or "failed (no result)"; `result` (only when ok) is what run_tune_step returned.
struct TuneStepOutcome {
  bool ok = false;
  std::string status;
  double seconds = 0.0;
  io::Json result;
};

// Runs the step `spec` (for people: `name`), giving up after `timeout_s`. A runner reports its own failures
// to the person (it knows the step's output); the tuner records every outcome in the report.
using TuneStepRunner = std::function<TuneStepOutcome(const std::string& name, const io::Json& spec, double timeout_s)>;

// One product kind's winner, for the closing summary.
struct GemmTuneWinner {
  GemmKind kind = GemmKind::other;
  std::string candidate;                  // e.g. "seed GEMMK=1 128x128 KREG8"
  double seconds = 0.0;                   // its time per training step on this kind's products
  std::optional<double> default_seconds;  // CLBlast's defaults on the same products, when they were timed
};

class GemmTuner {
 public:
  // `device` names the file's device and driver; `output_path` is where the tuning file goes. `log` receives
  // one line per finished step or decision; `should_stop` (optional) ends the search early (Ctrl-C).
  GemmTuner(const GemmTuneSettings& settings, const ocl::DeviceInfo& device, std::string output_path,
            TuneStepRunner run_step, LogFn log, std::function<bool()> should_stop = {});

  // The whole search within the time box, then the file is written a last time.
  void run();

  // Times a candidate on every product; keeps it per kind where it is the fastest correct one so far.
  void evaluate(const std::string& name, const ParameterSet& set);
  // The best set so far for `kind` (empty = CLBlast defaults).
  ParameterSet best_set(GemmKind kind) const;
  // The winners so far, in kind order.
  std::vector<GemmTuneWinner> winners() const;
  // Writes the winners and the report to output_path().
  void save();

  const std::string& output_path() const { return path_; }
  double seconds_left() const;

 private:
  struct Best {
    std::string name;
    ParameterSet set;
    double seconds = 0.0;
  };
  struct Evaluated {
    std::string name;
    ParameterSet set;
    double total = 0.0;  // seconds over all kinds, first timing
  };

  void remember_baseline();
  ParameterSet tune_helpers();
  void tune_gemm_kernels(const ParameterSet& helpers);
  std::optional<KernelParameters> tune_kernel(const std::string& tuner, size_t m, size_t n, size_t k, double fraction,
                                              double timeout_s);
  void score(const std::string& name, const ParameterSet& set, const TuneStepOutcome& outcome, io::Json entry);
  void note(const std::string& message) const;
  void second_round(double reserve_s);
  void choose_direct_switch(const ParameterSet& set);
  TuneStepOutcome run_step(const std::string& name, const io::Json& spec, double timeout_s);
  void skip_for_time(const std::string& name);  // recorded and told: too little of the time box left
  bool stopping() const { return should_stop_ && should_stop_(); }

  GemmTuneSettings settings_;
  ocl::DeviceInfo device_;
  std::string path_;
  TuneStepRunner run_step_;
  LogFn log_;
  std::function<bool()> should_stop_;
  std::chrono::steady_clock::time_point start_;
  std::vector<GemmProblem> problems_;
  std::vector<Evaluated> evaluated_;
  std::map<GemmKind, Best> best_;
  std::map<GemmKind, double> baseline_;
  io::Json report_;
};

// ---- the rules of the search, public so that tests can check them ----

// Hand-picked starting Xgemm sets, measured through the routine like every tuner result (they only enter the
// file if they win there).
std::vector<std::pair<std::string, KernelParameters>> gemm_seed_sets();

// CLBlast's GEMMK = 1 kernel computes wrong results when MWG ≠ NWG in some situations (fixed upstream in 2024,
// CNugteren/CLBlast pull request 543, after 1.5.3): seen here as wrong results, crashes, and a TuneXgemm winner
// whose results were garbage. Such sets are not timed on CLBlast versions before 1.6. The first form asks
// about the CLBlast this program was built against.
bool gemmk1_usable(const ParameterSet& set);
bool gemmk1_usable(const ParameterSet& set, int clblast_major, int clblast_minor);

// The direct/indirect switch from the crossover measurements: the forward product (rows[i] × W · W × W) took
// indirect_seconds[i] with the indirect kernel and direct_seconds[i] with the direct one. The indirect kernel
// should run from the first row count from which it is never slower; XGEMM_MIN_INDIRECT_SIZE is the cube root
// of that product's m·n·k (2^20, i.e. always direct, when it is slower even at the largest count).
struct DirectSwitch {
  std::optional<size_t> from_rows;  // none: the indirect kernel won at no measured size
  size_t min_indirect_size = size_t{1} << 20;
};
DirectSwitch direct_switch_from(const std::vector<size_t>& rows, const std::vector<double>& indirect_seconds,
                                const std::vector<double>& direct_seconds, size_t width);

// "Xgemm: GEMMK=1 KREG=8 ...; Copy: ..." ("CLBlast defaults" for an empty set).
std::string describe_parameter_set(const ParameterSet& set);

}  // namespace mipnerf::gemm
