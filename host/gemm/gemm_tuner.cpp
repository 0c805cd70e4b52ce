// The GEMM tune's search: the plan within the time box, scoring candidates, the winners and the report.
#include "gemm/gemm_tuner.hpp"

#include <clblast.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <tuple>

#include "core/duration.hpp"
#include "core/error.hpp"
#include "gemm/clblast_check.hpp"

namespace mipnerf::gemm {
namespace {

using io::Json;

// Configurations CLBlast 1.5.3's tuners draw from (counted from their parameter grids and constraints; the
// device's limits remove a few more), and roughly what one costs on PoCL (mostly compile time). Only used to
// pick the fraction that fits a step's share of the time box.
constexpr double kXgemmConfigurations = 120800.0 + 16566.0;  // variation 2 (GEMMK 0) + variation 12 (GEMMK 1)
constexpr double kXgemmDirectConfigurations = 8420.0;
constexpr double kSecondsPerGemmConfiguration = 2.0;

// The fraction of a tuner's configurations that fits `seconds`; at least ~8 GEMMK = 1 configurations (fewer
// and TuneXgemm's search may find no valid one).
double fraction_for(double seconds, double configurations) {
  return std::clamp(seconds / (configurations * kSecondsPerGemmConfiguration), 8.0 / 16566.0, 1.0);
}

constexpr GemmKind kTunedKinds[] = {GemmKind::forward, GemmKind::backward_data, GemmKind::backward_weights};

std::vector<double> doubles_of(const Json& array) {
  std::vector<double> values;
  for (const auto& v : array) values.push_back(v.get<double>());
  return values;
}

}  // namespace

GemmTuner::GemmTuner(const GemmTuneSettings& settings, const ocl::DeviceInfo& device, std::string output_path,
                     TuneStepRunner run_step, LogFn log, std::function<bool()> should_stop)
    : settings_(settings),
      device_(device),
      path_(std::move(output_path)),
      run_step_(std::move(run_step)),
      log_(std::move(log)),
      should_stop_(std::move(should_stop)),
      start_(std::chrono::steady_clock::now()) {
  if (!run_step_) throw Error("GemmTuner needs a step runner (it never touches the device itself)");
  if (settings.problems.empty()) throw Error("GemmTuner needs the products to tune for (GemmTuneSettings::problems)");
  problems_ = settings.problems;
  report_ = {{"rows", settings.rows},
             {"kernel_rows", settings.kernel_rows},
             {"time_box_minutes", settings.minutes},
             {"candidates", Json::array()},
             {"steps", Json::array()}};
  for (const auto& p : problems_) report_["problems"].push_back({{"label", p.label}, {"count", p.count}});
}

double GemmTuner::seconds_left() const {
  return settings_.minutes * 60.0 - std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void GemmTuner::note(const std::string& message) const {
  if (log_) log_(LogLevel::info, message);
}

void GemmTuner::run() {
  // 1. Defaults and starting sets.
  evaluate("CLBlast defaults", {});
  remember_baseline();
  for (const auto& [name, xgemm] : gemm_seed_sets()) evaluate(name, {{"Xgemm", xgemm}});
  // 2. The helper kernels, then every kind's best set so far with the tuned helpers.
  const ParameterSet helpers = tune_helpers();
  if (!helpers.empty()) {
    std::set<ParameterSet> tried;
    for (GemmKind kind : kTunedKinds) {
      ParameterSet set = best_set(kind);
      for (const auto& [name, values] : helpers) set[name] = values;
      if (tried.insert(set).second) evaluate(std::string("tuned helpers + best ") + gemm_kind_name(kind), set);
    }
  }
  // 3. The GEMM kernels themselves.
  tune_gemm_kernels(helpers);
  // 4. Every correct candidate timed once more (the time box permitting), then where the direct kernel should
  //    take over (small chunks), with the forward product's best set.
  second_round(150.0);
  choose_direct_switch(best_set(GemmKind::forward));
  save();
}

// The helper kernels, on the sizes of the matrices they move (Transpose on a square of the same size:
// CLBlast 1.5.3's TuneTranspose crashes on m ≠ n).
ParameterSet GemmTuner::tune_helpers() {
  const double budget = settings_.minutes * 60.0;
  const size_t W = settings_.width;
  // The helpers move whole matrices: tune them on 16,384 rows (parameters tuned on small matrices were slower
  // on the real ones here), capped by the rows of the timed products.
  const size_t helper_rows = std::min<size_t>(settings_.rows, 16384);
  size_t square = 64;
  while (square * square * 4 <= helper_rows * W) square *= 2;
  ParameterSet helpers;
  for (const auto& [name, m, n] : {std::tuple<const char*, size_t, size_t>{"Copy", helper_rows, W},
                                   {"Pad", helper_rows, W},
                                   {"Transpose", square, square},
                                   {"Padtranspose", helper_rows, W}}) {
    auto found = tune_kernel(name, m, n, 0, 1.0, std::min(seconds_left(), 0.06 * budget));
    if (found) helpers[name] = *found;
  }
  return helpers;
}

// TuneXgemm samples a fixed random subset of its configurations (the fraction sets its size) and returns the
// best GEMMK = 1 configuration it timed; each result is evaluated with the tuned helpers.
void GemmTuner::tune_gemm_kernels(const ParameterSet& helpers) {
  const double budget = settings_.minutes * 60.0;
  const size_t W = settings_.width, R = settings_.kernel_rows;
  // The forward shape (R×W·W×W) and the weight-gradient shape (Wᵀ·R: k = R), each with its share of the budget.
  struct XgemmShape {
    const char* name;
    size_t m, n, k;
    double budget_share;
  };
  for (const XgemmShape& shape : {XgemmShape{"TuneXgemm (forward shape)", R, W, W, 0.25},
                                  XgemmShape{"TuneXgemm (weight-gradient shape)", W, W, R, 0.15}}) {
    const double share = std::min(seconds_left() - 120.0, shape.budget_share * budget);
    if (auto found = tune_kernel("Xgemm", shape.m, shape.n, shape.k, fraction_for(share, kXgemmConfigurations),
                                 share * 1.5)) {
      ParameterSet set = helpers;
      set["Xgemm"] = *found;
      evaluate(shape.name, set);
    }
  }
  const double direct_share = std::min(seconds_left() - 90.0, 0.08 * budget);
  if (auto found = tune_kernel("XgemmDirect", R, W, W, fraction_for(direct_share, kXgemmDirectConfigurations),
                               direct_share * 1.5)) {
    // The direct kernel for every product (no pads or transposes at all): GemmRoutine's switch set above
    // any m·n·k of the MLP.
    ParameterSet set = helpers;
    set["XgemmDirect"] = *found;
    set["GemmRoutine"] = {{"XGEMM_MIN_INDIRECT_SIZE", 100000}};
    evaluate("TuneXgemmDirect, direct kernel for all", set);
  }
}

TuneStepOutcome GemmTuner::run_step(const std::string& name, const Json& spec, double timeout_s) {
  // Once stopped, no step starts (and none is recorded; the one that was running is).
  if (stopping()) return {false, "interrupted", 0.0, {}};
  TuneStepOutcome outcome = run_step_(name, spec, timeout_s);
  report_["steps"].push_back({{"step", name}, {"status", outcome.status}, {"seconds", outcome.seconds}});
  return outcome;
}

void GemmTuner::skip_for_time(const std::string& name) {
  report_["steps"].push_back({{"step", name}, {"status", "skipped: time box used up"}});
  note(name + ": skipped, the time box is used up");
}

// A kernel tuner; returns its full parameter set, or nothing when the step failed or did not fit.
std::optional<KernelParameters> GemmTuner::tune_kernel(const std::string& tuner, size_t m, size_t n, size_t k,
                                                       double fraction, double timeout_s) {
  timeout_s = std::min(timeout_s, seconds_left());  // never past the time box
  char what[160];
  std::snprintf(what, sizeof(what), "Tune%s %zux%zu%s, fraction %.4g", tuner.c_str(), m, n,
                k ? ("x" + std::to_string(k)).c_str() : "", fraction);
  if (timeout_s < 20.0) {
    skip_for_time(what);
    return std::nullopt;
  }
  const auto outcome = run_step(what, kernel_tuner_step(tuner, m, n, k, fraction), timeout_s);
  if (!outcome.ok) return std::nullopt;
  KernelParameters found;
  for (const auto& [name, value] : outcome.result.at("parameters").items()) found[name] = value.get<size_t>();
  note(std::string(what) + " → " + describe_parameter_set({{tuner, found}}) + " (" + format_duration(outcome.seconds) +
       ")");
  return found;
}

void GemmTuner::evaluate(const std::string& name, const ParameterSet& set) {
  if (!gemmk1_usable(set)) {
    note("evaluate " + name + ": skipped, GEMMK = 1 with MWG ≠ NWG (wrong results in CLBlast " + clblast_version() +
         ", fixed upstream by pull request 543)");
    report_["candidates"].push_back(
        {{"name", name}, {"parameters", parameter_set_json(set)}, {"status", "skipped: GEMMK = 1 with MWG != NWG"}});
    return;
  }
  const double timeout_s = std::min(seconds_left(), 300.0);
  if (timeout_s < 30.0) {
    skip_for_time("evaluate " + name);
    return;
  }
  const auto outcome = run_step("evaluate " + name, evaluate_step(set, problems_, 3), timeout_s);
  Json entry = {{"name", name}, {"parameters", parameter_set_json(set)}, {"status", outcome.status}};
  if (!outcome.ok) {
    report_["candidates"].push_back(entry);
    return;
  }
  score(name, set, outcome, std::move(entry));
}

// A candidate counts only when every product and the probe were correct; its time per kind is the sum over
// that kind's products of seconds × occurrences per step.
void GemmTuner::score(const std::string& name, const ParameterSet& set, const TuneStepOutcome& outcome, Json entry) {
  std::map<GemmKind, double> per_kind;
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
void GemmTuner::second_round(double reserve_s) {
  auto order = evaluated_;
  std::sort(order.begin(), order.end(), [](const Evaluated& a, const Evaluated& b) { return a.total < b.total; });
  for (const auto& c : order) {
    if (seconds_left() < reserve_s + 60.0 || stopping()) break;
    if (c.name.find("(again)") != std::string::npos) continue;
    evaluate(c.name + " (again)", c.set);
  }
}

// Finds the row count from which the indirect kernel (with `set`) beats the direct one on the forward product,
// and writes the matching XGEMM_MIN_INDIRECT_SIZE into each kind's best set that has none: products with
// m·n·k ≥ threshold³ then run indirect. Small products (the thin heads, the per-ray view product) stay direct.
void GemmTuner::choose_direct_switch(const ParameterSet& set) {
  const double timeout_s = std::min(seconds_left(), 240.0);
  if (timeout_s < 40.0 || best_.empty()) return;
  std::vector<size_t> rows;
  for (size_t r = 512; r <= 32768; r *= 2) rows.push_back(r);
  const auto outcome = run_step("direct/indirect crossover", crossover_step(set, settings_.width, rows), timeout_s);
  if (!outcome.ok) return;
  const Json& indirect = outcome.result.at("indirect");
  const Json& direct = outcome.result.at("direct");
  const DirectSwitch chosen = direct_switch_from(rows, doubles_of(indirect), doubles_of(direct), settings_.width);
  report_["direct_switch"] = {{"rows", rows},
                              {"indirect_seconds", indirect},
                              {"direct_seconds", direct},
                              {"XGEMM_MIN_INDIRECT_SIZE", chosen.min_indirect_size}};
  note("the indirect kernel wins from " +
       (chosen.from_rows ? std::to_string(*chosen.from_rows) + " rows" : std::string("no measured size")) +
       "; XGEMM_MIN_INDIRECT_SIZE = " + std::to_string(chosen.min_indirect_size));
  for (auto& [kind, best] : best_) {
    (void)kind;
    // A kind whose winner chose its own switch (the all-direct candidate) keeps it.
    if (!best.set.count("GemmRoutine"))
      best.set["GemmRoutine"] = {{"XGEMM_MIN_INDIRECT_SIZE", chosen.min_indirect_size}};
  }
  save();
}

ParameterSet GemmTuner::best_set(GemmKind kind) const {
  auto it = best_.find(kind);
  return it == best_.end() ? ParameterSet{} : it->second.set;
}

void GemmTuner::remember_baseline() {
  for (const auto& [kind, best] : best_) baseline_[kind] = best.seconds;
}

std::vector<GemmTuneWinner> GemmTuner::winners() const {
  std::vector<GemmTuneWinner> winners;
  for (const auto& [kind, best] : best_) {
    GemmTuneWinner winner{kind, best.name, best.seconds, std::nullopt};
    auto it = baseline_.find(kind);
    if (it != baseline_.end()) winner.default_seconds = it->second;
    winners.push_back(winner);
  }
  return winners;
}

void GemmTuner::save() {
  GemmTuning tuning;
  tuning.device_name = device_.name;
  tuning.driver_version = device_.driver_version;
  tuning.clblast_version = clblast_version();
  Json chosen = Json::object();
  for (const auto& [kind, best] : best_) {
    tuning.per_kind[kind] = best.set;
    chosen[gemm_kind_name(kind)] = {{"candidate", best.name}, {"seconds_per_step", best.seconds}};
  }
  report_["chosen"] = chosen;
  tuning.report_json = report_.dump();
  save_tuning(path_, tuning);
}

// ---- the rules ----

// GEMMK = 1 avoids the transposes of the big matrices in the forward and backward-data products; GEMMK = 0
// those of the weight gradient. Wide tiles suit CPUs (PoCL runs one work-item per loop).
std::vector<std::pair<std::string, KernelParameters>> gemm_seed_sets() {
  auto xgemm = [](size_t gemmk, size_t kreg, size_t mwg, size_t nwg, size_t kwg, size_t mdimc, size_t ndimc, size_t vwm,
                  size_t vwn, size_t kwi) {
    return KernelParameters{{"GEMMK", gemmk}, {"KREG", kreg},   {"MWG", mwg},     {"NWG", nwg},
                            {"KWG", kwg},     {"MDIMC", mdimc}, {"NDIMC", ndimc}, {"MDIMA", mdimc},
                            {"NDIMB", ndimc}, {"KWI", kwi},     {"VWM", vwm},     {"VWN", vwn},
                            {"STRM", 0},      {"STRN", 0},      {"SA", 0},        {"SB", 0}};
  };
  auto shared_b = xgemm(0, 1, 64, 128, 32, 8, 8, 8, 4, 2);
  shared_b["NDIMB"] = 16;
  shared_b["SB"] = 1;
  return {
      // GEMMK = 1 (no transposes in the forward and backward-data products), MWG = NWG (see gemmk1_usable),
      // 16×4 results per work-item: 82–88 GFLOP/s forward on 65,536×256×256 on PoCL's 2-core device here.
      {"seed GEMMK=1 128x128 KREG8", xgemm(1, 8, 128, 128, 1, 8, 32, 8, 4, 1)},
      {"seed GEMMK=1 64x64 KREG4", xgemm(1, 4, 64, 64, 1, 4, 16, 8, 4, 1)},
      // GEMMK = 0 (no transpose of the big matrices in the weight gradient): 8×16 results per work-item with
      // float16 loads of B, and a set an earlier TuneXgemm run found here (B through local memory).
      {"seed GEMMK=0 64x128 NWI16", xgemm(0, 1, 64, 128, 32, 8, 8, 8, 16, 2)},
      {"seed GEMMK=0 64x128 SB", shared_b},
  };
}

bool gemmk1_usable(const ParameterSet& set) { return gemmk1_usable(set, CLBLAST_VERSION_MAJOR, CLBLAST_VERSION_MINOR); }

bool gemmk1_usable(const ParameterSet& set, int clblast_major, int clblast_minor) {
  auto it = set.find("Xgemm");
  if (it == set.end() || it->second.count("GEMMK") == 0 || it->second.at("GEMMK") != 1) return true;
  const bool fixed = clblast_major > 1 || (clblast_major == 1 && clblast_minor >= 6);
  return fixed || it->second.at("MWG") == it->second.at("NWG");
}

DirectSwitch direct_switch_from(const std::vector<size_t>& rows, const std::vector<double>& indirect_seconds,
                                const std::vector<double>& direct_seconds, size_t width) {
  if (indirect_seconds.size() != rows.size() || direct_seconds.size() != rows.size()) {
    throw Error("the crossover step returned " + std::to_string(indirect_seconds.size()) + " indirect and " +
                std::to_string(direct_seconds.size()) + " direct timings for " + std::to_string(rows.size()) +
                " row counts");
  }
  size_t from = rows.size();  // the first row count from which indirect is never slower
  for (size_t i = rows.size(); i-- > 0;) {
    if (indirect_seconds[i] > direct_seconds[i]) break;
    from = i;
  }
  DirectSwitch chosen;
  if (from == rows.size()) return chosen;
  const double W = static_cast<double>(width);
  chosen.from_rows = rows[from];
  chosen.min_indirect_size = static_cast<size_t>(std::cbrt(static_cast<double>(rows[from]) * W * W));
  return chosen;
}

std::string describe_parameter_set(const ParameterSet& set) {
  if (set.empty()) return "CLBlast defaults";
  std::string text;
  for (const auto& [kernel, values] : set) {
    text += (text.empty() ? "" : "; ") + kernel + ":";
    for (const auto& [name, value] : values) text += " " + name + "=" + std::to_string(value);
  }
  return text;
}

}  // namespace mipnerf::gemm
