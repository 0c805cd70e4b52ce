// `mipnerf-cl tune`: measures CLBlast GEMM parameters for this device on the MLP's own products and stores the
// best in the per-device file every later run loads (host/mlp/gemm_tuning.hpp).
//
// Every piece of work that touches the device runs in a child process (this executable's hidden `__tune-step`
// subcommand): CLBlast's tuners compile hundreds of kernel variants and a driver can crash on one (PoCL does,
// e.g. TuneTranspose on a non-square matrix), which then costs that step only. The parent never runs OpenCL
// work; it plans the time box, starts each step with a deadline (killing it when it overruns), scores what the
// steps report, and rewrites the tuning file after every improvement, so an interrupted tune keeps its best.
//
// Steps: (1) the MLP's products timed with CLBlast's defaults and a few hand-picked starting sets; (2) the
// helper kernels the routine runs (TuneCopy, TunePad, TuneTranspose, TunePadtranspose); (3) TuneXgemm on the
// forward product and on the weight-gradient product, TuneXgemmDirect; (4) every candidate timed through the
// real routine (clblast::Gemm, row-major, with its pads and transposes) on the real shapes, results checked;
// per product kind (forward, backward data, backward weights) the fastest candidate is kept.
#include <clblast.h>
#include <csignal>
#include <filesystem>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <thread>
#include <tuple>

#include <nlohmann/json.hpp>

#include "cl/error.hpp"
#include "common.hpp"
#include "mlp/clblast_check.hpp"
#include "mlp/gemm.hpp"
#include "mlp/gemm_tuning.hpp"
#include "progress.hpp"

namespace mipnerf::cli {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

struct TuneArgs {
  double minutes = 30.0;         // the time box
  size_t rows = 65536;           // rows of the products timed through the routine
  size_t kernel_rows = 4096;     // rows of the kernel-level tuners (same tiles, shorter runs)
  size_t width = 256;            // the MLP's width W
  size_t input_width = 96;       // its input (IPE 96; NeRF 63)
  size_t view_branch_width = 128;
  bool no_view = false;
  std::string output;            // default: the per-device file
  bool if_missing = false;       // do nothing when the per-device file already exists (quick start re-runs)
};

struct StepArgs {
  std::string spec;
  std::string result;
};

// ---- helpers shared by both sides ----

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  if (!out) throw Error("cannot write " + path);
}

json set_json(const mlp::ParameterSet& set) {
  json j = json::object();
  for (const auto& [kernel, values] : set) j[kernel] = values;
  return j;
}

mlp::ParameterSet set_from(const json& j) {
  mlp::ParameterSet set;
  for (const auto& [kernel, values] : j.items()) {
    for (const auto& [name, value] : values.items()) set[kernel][name] = value.get<size_t>();
  }
  return set;
}

std::string describe_set(const mlp::ParameterSet& set) {
  if (set.empty()) return "CLBlast defaults";
  std::string text;
  for (const auto& [kernel, values] : set) {
    text += (text.empty() ? "" : "; ") + kernel + ":";
    for (const auto& [name, value] : values) text += " " + name + "=" + std::to_string(value);
  }
  return text;
}

// ==== the child: one step on the device ====

mlp::KernelParameters run_tuner(ocl::Context& ctx, const json& spec) {
  const std::string tuner = spec.at("tuner");
  const size_t m = spec.at("m"), n = spec.at("n"), k = spec.value("k", size_t{0});
  const double fraction = spec.at("fraction");
  std::unordered_map<std::string, size_t> params;
  cl_command_queue queue = ctx.raw_queue();
  clblast::StatusCode status = clblast::StatusCode::kUnknownError;
  if (tuner == "Xgemm") status = clblast::TuneXgemm<float>(&queue, m, n, k, fraction, params);
  else if (tuner == "XgemmDirect") status = clblast::TuneXgemmDirect<float>(&queue, m, n, k, fraction, params);
  else if (tuner == "Copy") status = clblast::TuneCopy<float>(&queue, m, n, fraction, params);
  else if (tuner == "Pad") status = clblast::TunePad<float>(&queue, m, n, fraction, params);
  else if (tuner == "Transpose") status = clblast::TuneTranspose<float>(&queue, m, n, fraction, params);
  else if (tuner == "Padtranspose") status = clblast::TunePadtranspose<float>(&queue, m, n, fraction, params);
  else throw Error("unknown tuner " + tuner);
  // TuneXgemm runs two searches (GEMMK = 0, then GEMMK = 1) into one map; when the second finds no valid
  // configuration it fails although the map holds the first one's best, which is still worth timing.
  if (status != clblast::StatusCode::kSuccess && tuner == "Xgemm" && params.count("GEMMK")) {
    std::cerr << "TuneXgemm: the GEMMK = 1 search failed (" << mlp::clblast_status_name(status)
              << "); keeping the GEMMK = 0 result\n";
    status = clblast::StatusCode::kSuccess;
  }
  mlp::check_clblast(status, "clblast::Tune" + tuner);
  // The tuners report only the parameters they vary; the rest keep CLBlast's values for this device.
  std::unordered_map<std::string, size_t> all;
  mlp::check_clblast(clblast::RetrieveParameters(ctx.raw_device(), tuner, clblast::Precision::kSingle, all),
                     "clblast::RetrieveParameters(" + tuner + ")");
  for (const auto& [name, value] : params) {
    if (all.count(name)) all[name] = value;
  }
  return {all.begin(), all.end()};
}

// Times each problem through mlp::gemm with the candidate installed (best of `reps` after a warm-up that
// compiles), and checks sampled elements of each result against a double dot product.
// Worst |error| / (2·k·u·Σ|a·b|) over every element of small products of awkward sizes (not multiples of any
// tile), each kind, computed with `set` and the indirect kernel forced (at these sizes CLBlast would otherwise
// run its direct kernel and the candidate's Xgemm would go unchecked). Correct results give ≈ 0.01.
double probe_correctness(ocl::Context& ctx, const mlp::ParameterSet& set) {
  mlp::GemmTuning forced;
  forced.common = set;
  forced.common["GemmRoutine"] = {{"XGEMM_MIN_INDIRECT_SIZE", 0}};
  mlp::install_gemm_tuning(ctx, forced);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> dist(-1.0f, 1.0f);
  double worst = 0.0;
  for (const auto& [m, n, k] : {std::tuple<size_t, size_t, size_t>{1000, 256, 96}, {333, 130, 257}, {96, 256, 1000}}) {
    for (int kind = 0; kind < 3; ++kind) {
      mlp::GemmShape s;
      s.m = m;
      s.n = n;
      s.k = k;
      s.transpose_a = kind == 2;
      s.transpose_b = kind == 1;
      std::vector<float> a(m * k), b(k * n);
      for (auto& v : a) v = dist(rng);
      for (auto& v : b) v = dist(rng);
      ocl::DeviceArray<float> a_dev(ctx, a.size(), "A"), b_dev(ctx, b.size(), "B"), c_dev(ctx, m * n, "C");
      a_dev.upload(ctx, a);
      b_dev.upload(ctx, b);
      const size_t lda = s.transpose_a ? m : k, ldb = s.transpose_b ? k : n;
      mlp::gemm(ctx, s, 1.0f, mlp::view(a_dev, lda), mlp::view(b_dev, ldb), 0.0f, mlp::view(c_dev, n), "probe");
      const auto c = c_dev.download(ctx);
      for (size_t i = 0; i < m; ++i) {
        for (size_t j = 0; j < n; ++j) {
          double sum = 0.0, magnitude = 0.0;
          for (size_t p = 0; p < k; ++p) {
            const double term = static_cast<double>(s.transpose_a ? a[p * lda + i] : a[i * lda + p]) *
                                (s.transpose_b ? b[j * ldb + p] : b[p * ldb + j]);
            sum += term;
            magnitude += std::abs(term);
          }
          const double error = std::abs(static_cast<double>(c[i * n + j]) - sum);
          worst = std::max(worst, std::isfinite(error) ? error / (2.0 * k * 5.96e-8 * magnitude + 1e-30) : 1e30);
        }
      }
    }
  }
  return worst;
}

json run_evaluate(ocl::Context& ctx, const json& spec) {
  mlp::GemmTuning candidate;
  candidate.common = set_from(spec.at("set"));
  const double probe_ratio = probe_correctness(ctx, candidate.common);
  std::cerr << "  correctness probe (indirect kernel forced): worst error ratio " << probe_ratio << "\n";
  mlp::install_gemm_tuning(ctx, candidate);
  const int reps = spec.value("reps", 3);
  size_t a_size = 0, b_size = 0, c_size = 0;
  std::vector<mlp::GemmShape> shapes;
  for (const auto& p : spec.at("problems")) {
    mlp::GemmShape s;
    s.m = p.at("m");
    s.n = p.at("n");
    s.k = p.at("k");
    s.transpose_a = p.at("ta");
    s.transpose_b = p.at("tb");
    shapes.push_back(s);
    a_size = std::max(a_size, s.m * s.k);
    b_size = std::max(b_size, s.k * s.n);
    c_size = std::max(c_size, s.m * s.n);
  }
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> dist(-1.0f, 1.0f);
  std::vector<float> a(a_size), b(b_size);
  for (auto& v : a) v = dist(rng);
  for (auto& v : b) v = dist(rng);
  ocl::DeviceArray<float> a_dev(ctx, a_size, "A"), b_dev(ctx, b_size, "B"), c_dev(ctx, c_size, "C");
  a_dev.upload(ctx, a);
  b_dev.upload(ctx, b);
  json times = json::array(), errors = json::array();
  for (const auto& s : shapes) {
    const size_t lda = s.transpose_a ? s.m : s.k, ldb = s.transpose_b ? s.k : s.n;
    auto product = [&] {
      mlp::gemm(ctx, s, 1.0f, mlp::view(a_dev, lda), mlp::view(b_dev, ldb), 0.0f, mlp::view(c_dev, s.n), "tune");
    };
    product();
    ctx.finish();
    // Correctness: 64 sampled elements within 2·k·u·Σ|a·b| (twice the worst-case float32 dot-product bound).
    std::vector<float> c(s.m * s.n);
    c_dev.download(ctx, c.data(), c.size());
    double worst_ratio = 0.0;
    std::uniform_int_distribution<size_t> pick_i(0, s.m - 1), pick_j(0, s.n - 1);
    for (int sample = 0; sample < 64; ++sample) {
      const size_t i = pick_i(rng), j = pick_j(rng);
      double sum = 0.0, magnitude = 0.0;
      for (size_t p = 0; p < s.k; ++p) {
        const double term = static_cast<double>(s.transpose_a ? a[p * lda + i] : a[i * lda + p]) *
                            (s.transpose_b ? b[j * ldb + p] : b[p * ldb + j]);
        sum += term;
        magnitude += std::abs(term);
      }
      const double bound = 2.0 * static_cast<double>(s.k) * 5.96e-8 * magnitude + 1e-30;
      const double error = std::abs(static_cast<double>(c[i * s.n + j]) - sum);
      worst_ratio = std::max(worst_ratio, std::isfinite(error) ? error / bound : 1e30);
    }
    errors.push_back(worst_ratio);
    double best = 1e30;
    for (int r = 0; r < reps; ++r) {
      const auto start = Clock::now();
      product();
      ctx.finish();
      best = std::min(best, std::chrono::duration<double>(Clock::now() - start).count());
    }
    times.push_back(best);
    std::cerr << "  " << s.m << "x" << s.n << "x" << s.k << " " << mlp::gemm_kind_name(mlp::gemm_kind(s)) << ": "
              << 2.0 * s.m * s.n * s.k / best * 1e-9 << " GFLOP/s\n";
  }
  return {{"seconds", times}, {"error_ratio", errors}, {"probe_error_ratio", probe_ratio}};
}

// CLBlast's direct/indirect switch: times the forward product (rows × W · W × W) for each row count with every
// product forced through the indirect kernel (XGEMM_MIN_INDIRECT_SIZE 0) and through the direct one (a
// threshold above any product), with the candidate's kernels.
json run_crossover(ocl::Context& ctx, const json& spec) {
  const mlp::ParameterSet base = set_from(spec.at("set"));
  const size_t width = spec.at("width");
  size_t max_rows = 0;
  for (const auto& r : spec.at("rows")) max_rows = std::max<size_t>(max_rows, r.get<size_t>());
  ocl::DeviceArray<float> a(ctx, max_rows * width, "A"), b(ctx, width * width, "B"), c(ctx, max_rows * width, "C");
  a.fill(ctx, 0.5f);
  b.fill(ctx, 0.25f);
  json indirect = json::array(), direct = json::array();
  for (const auto& r : spec.at("rows")) {
    mlp::GemmShape s;
    s.m = r.get<size_t>();
    s.n = s.k = width;
    for (const size_t threshold : {size_t{0}, size_t{1} << 20}) {
      mlp::GemmTuning t;
      t.common = base;
      t.common["GemmRoutine"] = {{"XGEMM_MIN_INDIRECT_SIZE", threshold}};
      mlp::install_gemm_tuning(ctx, t);
      double best = 1e30;
      for (int rep = 0; rep < 4; ++rep) {  // the first call builds the program
        const auto start = Clock::now();
        mlp::gemm(ctx, s, 1.0f, mlp::view(a, width), mlp::view(b, width), 0.0f, mlp::view(c, width), "crossover");
        ctx.finish();
        if (rep > 0) best = std::min(best, std::chrono::duration<double>(Clock::now() - start).count());
      }
      (threshold == 0 ? indirect : direct).push_back(best);
    }
    std::cerr << "  " << s.m << " rows: indirect " << indirect.back().get<double>() * 1e3 << " ms, direct "
              << direct.back().get<double>() * 1e3 << " ms\n";
  }
  return {{"indirect", indirect}, {"direct", direct}};
}

void run_step(const StepArgs& args) {
  const json spec = json::parse(read_text(args.spec));
  auto ctx = open_context();
  json result;
  const auto start = Clock::now();
  if (spec.at("type") == "tuner") {
    result["parameters"] = run_tuner(*ctx, spec);
  } else if (spec.at("type") == "crossover") {
    result = run_crossover(*ctx, spec);
  } else {
    result = run_evaluate(*ctx, spec);
  }
  result["wall_seconds"] = std::chrono::duration<double>(Clock::now() - start).count();
  const std::string temporary = args.result + ".part";
  write_text(temporary, result.dump());
  if (std::rename(temporary.c_str(), args.result.c_str()) != 0) throw Error("cannot write " + args.result);
}

// ==== the parent: plan, deadlines, scoring, the tuning file ====

std::atomic<bool> g_interrupted{false};
extern "C" void on_tune_interrupt(int) { g_interrupted = true; }

std::string self_path() {
  char buffer[4096];
  const ssize_t n = ::readlink("/proc/self/exe", buffer, sizeof(buffer) - 1);
  if (n <= 0) throw Error("cannot find this executable (/proc/self/exe) to start the tuning steps");
  return std::string(buffer, static_cast<size_t>(n));
}

struct StepOutcome {
  bool ok = false;
  std::string status;  // "ok", "timed out", "crashed (signal 11)", "failed (exit 1)"
  double seconds = 0.0;
  json result;
};

// CLBlast's GEMMK = 1 kernel computes wrong results when MWG ≠ NWG in some situations (fixed upstream in 2024,
// CNugteren/CLBlast pull request 543, after 1.5.3): seen here as wrong results, crashes, and a TuneXgemm winner
// whose results were garbage. Such sets are not timed on CLBlast versions before 1.6.
bool gemmk1_usable(const mlp::ParameterSet& set) {
  auto it = set.find("Xgemm");
  if (it == set.end() || it->second.count("GEMMK") == 0 || it->second.at("GEMMK") != 1) return true;
  const bool fixed = CLBLAST_VERSION_MAJOR > 1 || CLBLAST_VERSION_MINOR >= 6;
  return fixed || it->second.at("MWG") == it->second.at("NWG");
}

class Tuner {
 public:
  Tuner(const TuneArgs& args, const ocl::DeviceInfo& device)
      : args_(args),
        device_(device),
        exe_(self_path()),
        start_(Clock::now()),
        progress_("tune", static_cast<int64_t>(args.minutes * 60.0)) {
    char pattern[] = "/tmp/mipnerf-tune-XXXXXX";
    if (!::mkdtemp(pattern)) throw Error("cannot create a temporary folder under /tmp for the tuning steps");
    work_ = pattern;
    mlp::MlpConfig config;
    config.width = args.width;
    config.input_width = args.input_width;
    config.view_branch_width = args.view_branch_width;
    config.bottleneck_width = args.width;
    config.view_dependence = !args.no_view;
    problems_ = mlp::mlp_gemm_problems(config, args.rows);
    path_ = args.output.empty() ? mlp::tuning_file_path(device) : args.output;
    report_ = {{"rows", args.rows}, {"kernel_rows", args.kernel_rows}, {"time_box_minutes", args.minutes},
               {"candidates", json::array()}, {"steps", json::array()}};
    for (const auto& p : problems_) report_["problems"].push_back({{"label", p.label}, {"count", p.count}});
  }
  ~Tuner() {
    std::string command = "rm -rf '" + work_ + "'";
    if (std::system(command.c_str()) != 0) std::cerr << "mipnerf-cl: could not remove " << work_ << "\n";
  }

  double elapsed() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

  // A finished line above the progress line (which redraws itself below it).
  void note(const std::string& message) const {
    std::cerr << (isatty(STDERR_FILENO) ? "\r\033[K" : "") << "mipnerf-cl: tune: " << message << "\n";
  }
  void finish_progress() { progress_.finish("done"); }
  double left() const { return args_.minutes * 60.0 - elapsed(); }
  const std::string& path() const { return path_; }

  // Runs one step in a child with a deadline, showing the overall progress while it runs.
  StepOutcome run(const std::string& name, const json& spec, double timeout_s) {
    StepOutcome outcome;
    if (g_interrupted) {
      outcome.status = "interrupted";
      return outcome;
    }
    const std::string id = std::to_string(step_count_++);
    const std::string spec_path = work_ + "/step" + id + ".json", result_path = work_ + "/result" + id + ".json";
    const std::string log_path = work_ + "/step" + id + ".log";
    write_text(spec_path, spec.dump());
    std::vector<std::string> argv_text = {exe_, "--device", std::to_string(device_.index), "__tune-step", "--spec",
                                          spec_path, "--result", result_path};
    // Everything the child needs is prepared before fork(): between fork and exec only async-signal-safe
    // calls (the OpenCL runtime may have started threads in this process).
    std::vector<char*> argv;
    for (auto& a : argv_text) argv.push_back(a.data());
    argv.push_back(nullptr);
    const int log_fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (log_fd < 0) throw Error("cannot create " + log_path);
    const auto started = Clock::now();
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
    int status = 0;
    bool timed_out = false;
    while (true) {
      const pid_t done = ::waitpid(pid, &status, WNOHANG);
      if (done == pid) break;
      const double running = std::chrono::duration<double>(Clock::now() - started).count();
      if (running > timeout_s || g_interrupted) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
        timed_out = !g_interrupted;
        break;
      }
      progress_.update(static_cast<int64_t>(std::min(elapsed(), args_.minutes * 60.0)),
                       name + " (" + format_duration(running) + " of at most " + format_duration(timeout_s) + ")");
      std::this_thread::sleep_for(std::chrono::milliseconds(250));
    }
    outcome.seconds = std::chrono::duration<double>(Clock::now() - started).count();
    if (g_interrupted) {
      outcome.status = "interrupted";
    } else if (timed_out) {
      outcome.status = "timed out after " + format_duration(timeout_s);
    } else if (WIFSIGNALED(status)) {
      outcome.status = "crashed (signal " + std::to_string(WTERMSIG(status)) + ")";
    } else if (WIFEXITED(status) && WEXITSTATUS(status) != 0) {
      outcome.status = "failed (exit " + std::to_string(WEXITSTATUS(status)) + ")";
    } else {
      try {
        outcome.result = json::parse(read_text(result_path));
        outcome.ok = true;
        outcome.status = "ok";
      } catch (const std::exception&) {
        outcome.status = "failed (no result)";
      }
    }
    if (!outcome.ok && outcome.status != "interrupted") {
      const std::string log = read_text(log_path);
      const auto last_line = log.find_last_of('\n', log.size() >= 2 ? log.size() - 2 : 0);
      note(name + " " + outcome.status +
           (log.empty() ? "" : ": " + log.substr(last_line == std::string::npos ? 0 : last_line + 1)));
    }
    report_["steps"].push_back({{"step", name}, {"status", outcome.status}, {"seconds", outcome.seconds}});
    return outcome;
  }

  // A kernel tuner; returns its full parameter set, or nothing when the step failed.
  std::optional<mlp::KernelParameters> tune_kernel(const std::string& tuner, size_t m, size_t n, size_t k,
                                                   double fraction, double timeout_s) {
    timeout_s = std::min(timeout_s, left());  // never past the time box
    char what[160];
    std::snprintf(what, sizeof(what), "Tune%s %zux%zu%s, fraction %.4g", tuner.c_str(), m, n,
                  k ? ("x" + std::to_string(k)).c_str() : "", fraction);
    if (timeout_s < 20.0) {
      report_["steps"].push_back({{"step", what}, {"status", "skipped: time box used up"}});
      note(std::string(what) + ": skipped, the time box is used up");
      return std::nullopt;
    }
    const auto outcome =
        run(what, {{"type", "tuner"}, {"tuner", tuner}, {"m", m}, {"n", n}, {"k", k}, {"fraction", fraction}},
            timeout_s);
    if (!outcome.ok) return std::nullopt;
    mlp::KernelParameters found;
    for (const auto& [name, value] : outcome.result.at("parameters").items()) found[name] = value.get<size_t>();
    note(std::string(what) + " → " + describe_set({{tuner, found}}) + " (" + format_duration(outcome.seconds) + ")");
    return found;
  }

  // Times a candidate on every problem; keeps it per kind where it is the fastest so far.
  void evaluate(const std::string& name, const mlp::ParameterSet& set) {
    if (!gemmk1_usable(set)) {
      note("evaluate " + name + ": skipped, GEMMK = 1 with MWG ≠ NWG (wrong results in CLBlast " +
           mlp::clblast_version() + ", fixed upstream by pull request 543)");
      report_["candidates"].push_back({{"name", name}, {"parameters", set_json(set)},
                                       {"status", "skipped: GEMMK = 1 with MWG != NWG"}});
      return;
    }
    const double timeout_s = std::min(left(), 300.0);
    if (timeout_s < 30.0) {
      report_["steps"].push_back({{"step", "evaluate " + name}, {"status", "skipped: time box used up"}});
      note("evaluate " + name + ": skipped, the time box is used up");
      return;
    }
    json problems = json::array();
    for (const auto& p : problems_) {
      problems.push_back({{"m", p.shape.m}, {"n", p.shape.n}, {"k", p.shape.k}, {"ta", p.shape.transpose_a},
                          {"tb", p.shape.transpose_b}});
    }
    const auto outcome =
        run("evaluate " + name, {{"type", "evaluate"}, {"set", set_json(set)}, {"problems", problems}, {"reps", 3}},
            timeout_s);
    json entry = {{"name", name}, {"parameters", set_json(set)}, {"status", outcome.status}};
    if (!outcome.ok) {
      report_["candidates"].push_back(entry);
      return;
    }
    std::map<mlp::GemmKind, double> per_kind;
    bool correct = outcome.result.value("probe_error_ratio", 1e30) <= 1.0;
    std::string summary;
    for (size_t i = 0; i < problems_.size(); ++i) {
      const double seconds = outcome.result.at("seconds")[i], ratio = outcome.result.at("error_ratio")[i];
      correct = correct && ratio <= 1.0;
      per_kind[problems_[i].kind()] += seconds * static_cast<double>(problems_[i].count);
      const double gflops = problems_[i].flops() / seconds * 1e-9;
      entry["gflops"][problems_[i].label] = gflops;
      char text[96];
      std::snprintf(text, sizeof(text), "%s%s %.1f", summary.empty() ? "" : ", ", problems_[i].label.c_str(), gflops);
      summary += text;
    }
    entry["correct"] = correct;
    report_["candidates"].push_back(entry);
    note(name + (correct ? "" : " (WRONG RESULTS, discarded)") + ": GFLOP/s " + summary);
    if (!correct) return;
    double total = 0.0;
    for (const auto& [kind, seconds] : per_kind) total += seconds;
    evaluated_.push_back({name, set, total});
    bool improved = false;
    for (const auto& [kind, seconds] : per_kind) {
      auto it = best_.find(kind);
      if (it == best_.end() || seconds < it->second.seconds) {
        best_[kind] = {name, set, seconds};
        improved = true;
      }
    }
    if (improved) save();
  }

  // The machine may have been busy while a candidate was timed (other processes on a shared CPU): time the
  // correct candidates again, fastest first, while `reserve_s` of the time box stays free. A kind keeps the
  // fastest time any candidate showed.
  void second_round(double reserve_s) {
    auto order = evaluated_;
    std::sort(order.begin(), order.end(), [](const Evaluated& a, const Evaluated& b) { return a.total < b.total; });
    for (const auto& c : order) {
      if (left() < reserve_s + 60.0 || g_interrupted) break;
      if (c.name.find("(again)") != std::string::npos) continue;
      evaluate(c.name + " (again)", c.set);
    }
  }

  // Finds the row count from which the indirect kernel (with `set`) beats the direct one on the forward
  // product, and writes the matching XGEMM_MIN_INDIRECT_SIZE into each kind's best set that has none: products with
  // m·n·k ≥ threshold³ then run indirect. Small products (the thin heads, the per-ray view product) stay direct.
  void choose_direct_switch(const mlp::ParameterSet& set) {
    const double timeout_s = std::min(left(), 240.0);
    if (timeout_s < 40.0 || best_.empty()) return;
    json rows = json::array();
    for (size_t r = 512; r <= 32768; r *= 2) rows.push_back(r);
    const auto outcome =
        run("direct/indirect crossover", {{"type", "crossover"}, {"set", set_json(set)}, {"width", args_.width},
                                           {"rows", rows}},
            timeout_s);
    if (!outcome.ok) return;
    const json& indirect = outcome.result.at("indirect");
    const json& direct = outcome.result.at("direct");
    size_t from = rows.size();  // the first row count from which indirect is never slower
    for (size_t i = rows.size(); i-- > 0;) {
      if (indirect[i].get<double>() > direct[i].get<double>()) break;
      from = i;
    }
    const double W = static_cast<double>(args_.width);
    const size_t threshold = from == rows.size() ? size_t{1} << 20
                                                 : static_cast<size_t>(std::cbrt(rows[from].get<double>() * W * W));
    report_["direct_switch"] = {{"rows", rows}, {"indirect_seconds", indirect}, {"direct_seconds", direct},
                                {"XGEMM_MIN_INDIRECT_SIZE", threshold}};
    note("the indirect kernel wins from " +
         (from == rows.size() ? std::string("no measured size") : rows[from].dump() + " rows") +
         "; XGEMM_MIN_INDIRECT_SIZE = " + std::to_string(threshold));
    for (auto& [kind, best] : best_) {
      (void)kind;
      // A kind whose winner chose its own switch (the all-direct candidate) keeps it.
      if (!best.set.count("GemmRoutine")) best.set["GemmRoutine"] = {{"XGEMM_MIN_INDIRECT_SIZE", threshold}};
    }
    save();
  }

  // The best set so far for `kind` (empty = CLBlast defaults).
  mlp::ParameterSet best_set(mlp::GemmKind kind) const {
    auto it = best_.find(kind);
    return it == best_.end() ? mlp::ParameterSet{} : it->second.set;
  }

  void save() {
    mlp::GemmTuning tuning;
    tuning.device_name = device_.name;
    tuning.driver_version = device_.driver_version;
    tuning.clblast_version = mlp::clblast_version();
    json chosen = json::object();
    for (const auto& [kind, best] : best_) {
      tuning.per_kind[kind] = best.set;
      chosen[mlp::gemm_kind_name(kind)] = {{"candidate", best.name}, {"seconds_per_step", best.seconds}};
    }
    report_["chosen"] = chosen;
    tuning.report_json = report_.dump();
    mlp::save_tuning(path_, tuning);
  }

  void summary() const {
    std::cout << "GEMM parameters for " << device_.name << " (" << mlp::clblast_version() << "), time per step of "
              << "the MLP's products at " << args_.rows << " rows:\n";
    for (const auto& [kind, best] : best_) {
      std::printf("  %-17s %8.3f s  %s", mlp::gemm_kind_name(kind), best.seconds, best.name.c_str());
      auto it = baseline_.find(kind);
      if (it != baseline_.end() && it->second > 0) {
        std::printf("  (CLBlast defaults %.3f s: %.2fx faster)", it->second, it->second / best.seconds);
      }
      std::printf("\n");
    }
    std::cout << "written to " << path_ << "\n";
  }

  void remember_baseline() {
    for (const auto& [kind, best] : best_) baseline_[kind] = best.seconds;
  }

 private:
  struct Best {
    std::string name;
    mlp::ParameterSet set;
    double seconds = 0.0;
  };
  struct Evaluated {
    std::string name;
    mlp::ParameterSet set;
    double total = 0.0;  // seconds over all kinds, first timing
  };
  std::vector<Evaluated> evaluated_;
  TuneArgs args_;
  ocl::DeviceInfo device_;
  std::string exe_;
  std::string work_;
  std::string path_;
  Clock::time_point start_;
  Progress progress_;
  std::vector<mlp::GemmProblem> problems_;
  std::map<mlp::GemmKind, Best> best_;
  std::map<mlp::GemmKind, double> baseline_;
  json report_;
  int step_count_ = 0;
};

// Hand-picked starting sets, measured through the routine like every tuner result (they only enter the file
// if they win there). GEMMK = 1 avoids the transposes of the big matrices in the forward and backward-data
// products; GEMMK = 0 those of the weight gradient. Wide tiles suit CPUs (PoCL runs one work-item per loop).
std::vector<std::pair<std::string, mlp::KernelParameters>> seed_sets() {
  auto xgemm = [](size_t gemmk, size_t kreg, size_t mwg, size_t nwg, size_t kwg, size_t mdimc, size_t ndimc,
                  size_t vwm, size_t vwn, size_t kwi) {
    return mlp::KernelParameters{{"GEMMK", gemmk}, {"KREG", kreg}, {"MWG", mwg},     {"NWG", nwg},
                                 {"KWG", kwg},     {"MDIMC", mdimc}, {"NDIMC", ndimc}, {"MDIMA", mdimc},
                                 {"NDIMB", ndimc}, {"KWI", kwi},   {"VWM", vwm},     {"VWN", vwn},
                                 {"STRM", 0},      {"STRN", 0},    {"SA", 0},        {"SB", 0}};
  };
  return {
      // GEMMK = 1 (no transposes in the forward and backward-data products), MWG = NWG (see gemmk1_usable),
      // 16×4 results per work-item: 82–88 GFLOP/s forward on 65,536×256×256 on PoCL's 2-core device here.
      {"seed GEMMK=1 128x128 KREG8", xgemm(1, 8, 128, 128, 1, 8, 32, 8, 4, 1)},
      {"seed GEMMK=1 64x64 KREG4", xgemm(1, 4, 64, 64, 1, 4, 16, 8, 4, 1)},
      // GEMMK = 0 (no transpose of the big matrices in the weight gradient): 8×16 results per work-item with
      // float16 loads of B, and a set an earlier TuneXgemm run found here (B through local memory).
      {"seed GEMMK=0 64x128 NWI16", xgemm(0, 1, 64, 128, 32, 8, 8, 8, 16, 2)},
      {"seed GEMMK=0 64x128 SB", [&] {
         auto p = xgemm(0, 1, 64, 128, 32, 8, 8, 8, 4, 2);
         p["NDIMB"] = 16;
         p["SB"] = 1;
         return p;
       }()},
  };
}

// Configurations CLBlast 1.5.3's tuners draw from (counted from their parameter grids and constraints; the
// device's limits remove a few more), and roughly what one costs on PoCL (mostly compile time). Only used to
// pick the fraction that fits a step's share of the time box.
constexpr double kXgemmConfigurations = 120800.0 + 16566.0;  // variation 2 (GEMMK 0) + variation 12 (GEMMK 1)
constexpr double kXgemmDirectConfigurations = 8420.0;
constexpr double kSecondsPerGemmConfiguration = 2.0;

void run_tune(const TuneArgs& args) {
  if (args.minutes <= 0) throw Error("--minutes must be positive");
  if (args.rows % 64 != 0 || args.kernel_rows % 128 != 0 || args.rows == 0 || args.kernel_rows == 0) {
    throw Error("--rows must be a multiple of 64 and --kernel-rows of 128 (CLBlast's tuners need whole tiles)");
  }
  if (args.width % 128 != 0) throw Error("--width must be a multiple of 128 for CLBlast's Xgemm tuner");
  const auto devices = ocl::list_devices();
  const ocl::DeviceInfo device = ocl::choose_device(devices, global_options().device);
  if (args.if_missing) {
    const std::string existing = args.output.empty() ? mlp::tuning_file_path(device) : args.output;
    if (std::filesystem::exists(existing)) {
      std::cerr << "mipnerf-cl: tune: " << existing << " exists; nothing to do (--if-missing)\n";
      return;
    }
  }
  Tuner tuner(args, device);
  std::signal(SIGINT, on_tune_interrupt);
  std::signal(SIGTERM, on_tune_interrupt);
  std::cerr << "mipnerf-cl: tune: " << device.name << ", CLBlast " << mlp::clblast_version() << ", time box "
            << format_duration(args.minutes * 60.0) << "; every step runs in its own process; results go to "
            << tuner.path() << "\n";

  // 1. Defaults and starting sets.
  tuner.evaluate("CLBlast defaults", {});
  tuner.remember_baseline();
  for (const auto& [name, xgemm] : seed_sets()) tuner.evaluate(name, {{"Xgemm", xgemm}});

  // 2. The helper kernels, on the sizes of the matrices they move (Transpose on a square of the same size:
  //    CLBlast 1.5.3's TuneTranspose crashes on m ≠ n).
  const double budget = args.minutes * 60.0;
  const size_t W = args.width, R = args.kernel_rows;
  // The helpers move whole matrices: tune them on 16,384 rows (parameters tuned on small matrices were slower
  // on the real ones here), capped by --rows.
  const size_t helper_rows = std::min<size_t>(args.rows, 16384);
  size_t square = 64;
  while (square * square * 4 <= helper_rows * W) square *= 2;
  mlp::ParameterSet helpers;
  for (const auto& [name, m, n] :
       {std::tuple<const char*, size_t, size_t>{"Copy", helper_rows, W}, {"Pad", helper_rows, W},
        {"Transpose", square, square}, {"Padtranspose", helper_rows, W}}) {
    auto found = tuner.tune_kernel(name, m, n, 0, 1.0, std::min(tuner.left(), 0.06 * budget));
    if (found) helpers[name] = *found;
  }
  // Every kind's best set so far, with the tuned helpers.
  if (!helpers.empty()) {
    std::set<mlp::ParameterSet> tried;
    for (auto kind : {mlp::GemmKind::forward, mlp::GemmKind::backward_data, mlp::GemmKind::backward_weights}) {
      mlp::ParameterSet set = tuner.best_set(kind);
      for (const auto& [name, values] : helpers) set[name] = values;
      if (tried.insert(set).second) tuner.evaluate(std::string("tuned helpers + best ") + mlp::gemm_kind_name(kind), set);
    }
  }

  // 3. The GEMM kernels themselves. TuneXgemm samples a fixed random subset of its configurations (the
  //    fraction sets its size) and returns the best GEMMK = 1 configuration it timed.
  // At least ~8 GEMMK = 1 configurations (fewer and its search may find no valid one).
  auto fraction_for = [](double seconds, double configurations) {
    return std::clamp(seconds / (configurations * kSecondsPerGemmConfiguration), 8.0 / 16566.0, 1.0);
  };
  const double forward_share = std::min(tuner.left() - 120.0, 0.25 * budget);
  if (auto found = tuner.tune_kernel("Xgemm", R, W, W, fraction_for(forward_share, kXgemmConfigurations),
                                     forward_share * 1.5)) {
    mlp::ParameterSet set = helpers;
    set["Xgemm"] = *found;
    tuner.evaluate("TuneXgemm (forward shape)", set);
  }
  const double weights_share = std::min(tuner.left() - 120.0, 0.15 * budget);
  if (auto found = tuner.tune_kernel("Xgemm", W, W, R, fraction_for(weights_share, kXgemmConfigurations),
                                     weights_share * 1.5)) {
    mlp::ParameterSet set = helpers;
    set["Xgemm"] = *found;
    tuner.evaluate("TuneXgemm (weight-gradient shape)", set);
  }
  const double direct_share = std::min(tuner.left() - 90.0, 0.08 * budget);
  if (auto found = tuner.tune_kernel("XgemmDirect", R, W, W, fraction_for(direct_share, kXgemmDirectConfigurations),
                                     direct_share * 1.5)) {
    // The direct kernel for every product (no pads or transposes at all): GemmRoutine's switch set above
    // any m·n·k of the MLP.
    mlp::ParameterSet set = helpers;
    set["XgemmDirect"] = *found;
    set["GemmRoutine"] = {{"XGEMM_MIN_INDIRECT_SIZE", 100000}};
    tuner.evaluate("TuneXgemmDirect, direct kernel for all", set);
  }
  // 4. Every correct candidate timed once more (the time box permitting), then where the direct kernel should
  //    take over (small chunks), with the forward product's best set.
  tuner.second_round(150.0);
  tuner.choose_direct_switch(tuner.best_set(mlp::GemmKind::forward));
  tuner.save();
  tuner.finish_progress();
  tuner.summary();
  if (g_interrupted) throw Error("tune interrupted; the best parameters found so far are in " + tuner.path());
}

}  // namespace

void register_tune(CLI::App& app) {
  auto args = std::make_shared<TuneArgs>();
  auto* cmd = app.add_subcommand(
      "tune", "Measure CLBlast GEMM parameters for this device on the MLP's products and store the best "
              "(loaded automatically by later runs)");
  cmd->add_option("--minutes", args->minutes, "Time box for the whole tune")->capture_default_str();
  cmd->add_option("--rows", args->rows, "Rows (samples) of the products timed through CLBlast's routine")
      ->capture_default_str();
  cmd->add_option("--kernel-rows", args->kernel_rows, "Rows of the kernel-level tuners (multiple of 128)")
      ->capture_default_str();
  cmd->add_option("--width", args->width, "MLP width W")->capture_default_str();
  cmd->add_option("--input-width", args->input_width, "MLP input features (IPE: 96, NeRF PE: 63)")
      ->capture_default_str();
  cmd->add_option("--view-branch-width", args->view_branch_width, "Width of the view branch")->capture_default_str();
  cmd->add_flag("--no-view", args->no_view, "The MLP has no view branch");
  cmd->add_option("--output", args->output, "Write the parameters here instead of the per-device cache file");
  cmd->add_flag("--if-missing", args->if_missing, "Do nothing when the tuning file already exists");
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
