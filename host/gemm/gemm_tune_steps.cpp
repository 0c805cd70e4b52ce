// The GEMM tune's steps on the device: CLBlast's tuners, a candidate timed and checked through mlp::gemm, and
// the direct/indirect crossover.
#include "gemm/gemm_tune_steps.hpp"

#include <clblast.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <sstream>
#include <tuple>
#include <unordered_map>

#include "cl/buffer.hpp"
#include "core/error.hpp"
#include "gemm/clblast_check.hpp"
#include "gemm/gemm.hpp"

namespace mipnerf::gemm {
namespace {

using Clock = std::chrono::steady_clock;
using io::Json;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

template <typename Value>
std::string text_of(const Value& value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

// ---- kernel tuner ----

clblast::StatusCode call_tuner(cl_command_queue* queue, const std::string& tuner, size_t m, size_t n, size_t k,
                               double fraction, std::unordered_map<std::string, size_t>& params) {
  if (tuner == "Xgemm") return clblast::TuneXgemm<float>(queue, m, n, k, fraction, params);
  if (tuner == "XgemmDirect") return clblast::TuneXgemmDirect<float>(queue, m, n, k, fraction, params);
  if (tuner == "Copy") return clblast::TuneCopy<float>(queue, m, n, fraction, params);
  if (tuner == "Pad") return clblast::TunePad<float>(queue, m, n, fraction, params);
  if (tuner == "Transpose") return clblast::TuneTranspose<float>(queue, m, n, fraction, params);
  if (tuner == "Padtranspose") return clblast::TunePadtranspose<float>(queue, m, n, fraction, params);
  throw Error("unknown tuner " + tuner);
}

Json run_kernel_tuner(ocl::Context& ctx, const Json& spec, const LogFn& log) {
  const std::string tuner = spec.at("tuner");
  const size_t m = spec.at("m"), n = spec.at("n"), k = spec.value("k", size_t{0});
  std::unordered_map<std::string, size_t> params;
  cl_command_queue queue = ctx.raw_queue();
  clblast::StatusCode status = call_tuner(&queue, tuner, m, n, k, spec.at("fraction").get<double>(), params);
  // TuneXgemm runs two searches (GEMMK = 0, then GEMMK = 1) into one map; when the second finds no valid
  // configuration it fails although the map holds the first one's best, which is still worth timing.
  if (status != clblast::StatusCode::kSuccess && tuner == "Xgemm" && params.count("GEMMK")) {
    if (log) {
      log(LogLevel::warning,
          "TuneXgemm: the GEMMK = 1 search failed (" + clblast_status_name(status) + "); keeping the GEMMK = 0 result");
    }
    status = clblast::StatusCode::kSuccess;
  }
  check_clblast(status, "clblast::Tune" + tuner);
  // The tuners report only the parameters they vary; the rest keep CLBlast's values for this device.
  std::unordered_map<std::string, size_t> all;
  check_clblast(clblast::RetrieveParameters(ctx.raw_device(), tuner, clblast::Precision::kSingle, all),
                "clblast::RetrieveParameters(" + tuner + ")");
  for (const auto& [name, value] : params) {
    if (all.count(name)) all[name] = value;
  }
  return {{"parameters", KernelParameters(all.begin(), all.end())}};
}

// ---- evaluate: a candidate through the real routine ----

// Host copies of a product's operands, row-major, with their leading dimensions.
struct OperandViews {
  const std::vector<float>& a;
  const std::vector<float>& b;
  size_t lda, ldb;
};

OperandViews operands_of(const GemmShape& s, const std::vector<float>& a, const std::vector<float>& b) {
  return {a, b, s.transpose_a ? s.m : s.k, s.transpose_b ? s.k : s.n};
}

// Element (i, j) of op(A)·op(B) in double, with Σ|a·b| for its error bound.
std::pair<double, double> exact_element(const GemmShape& s, const OperandViews& x, size_t i, size_t j) {
  double sum = 0.0, magnitude = 0.0;
  for (size_t p = 0; p < s.k; ++p) {
    const double term = static_cast<double>(s.transpose_a ? x.a[p * x.lda + i] : x.a[i * x.lda + p]) *
                        (s.transpose_b ? x.b[j * x.ldb + p] : x.b[p * x.ldb + j]);
    sum += term;
    magnitude += std::abs(term);
  }
  return {sum, magnitude};
}

void run_gemm(ocl::Context& ctx, const GemmShape& s, const ocl::DeviceArray<float>& a, const ocl::DeviceArray<float>& b,
              ocl::DeviceArray<float>& c, const char* label) {
  const size_t lda = s.transpose_a ? s.m : s.k, ldb = s.transpose_b ? s.k : s.n;
  sgemm(ctx, GemmBackend::clblast, s, 1.0f, view(a, lda), view(b, ldb), 0.0f, view(c, s.n), label);
}

std::vector<float> random_values(size_t count, std::mt19937& rng) {
  std::uniform_real_distribution<float> dist(-1.0f, 1.0f);
  std::vector<float> values(count);
  for (auto& v : values) v = dist(rng);
  return values;
}

// Worst error ratio over every element of small products of awkward sizes (not multiples of any tile), each
// kind, computed with `set` and the indirect kernel forced (at these sizes CLBlast would otherwise run its
// direct kernel and the candidate's Xgemm would go unchecked). Correct results give ≈ 0.01.
double probe_correctness(ocl::Context& ctx, const ParameterSet& set) {
  GemmTuning forced;
  forced.common = set;
  forced.common["GemmRoutine"] = {{"XGEMM_MIN_INDIRECT_SIZE", 0}};
  install_gemm_tuning(ctx, forced);
  std::mt19937 rng(9);
  double worst = 0.0;
  for (const auto& [m, n, k] : {std::tuple<size_t, size_t, size_t>{1000, 256, 96}, {333, 130, 257}, {96, 256, 1000}}) {
    for (int kind = 0; kind < 3; ++kind) {
      const GemmShape s = gemm_shape(m, n, k, kind == 2, kind == 1);
      const std::vector<float> a = random_values(m * k, rng), b = random_values(k * n, rng);
      ocl::DeviceArray<float> a_dev(ctx, a.size(), "A"), b_dev(ctx, b.size(), "B"), c_dev(ctx, m * n, "C");
      a_dev.upload(ctx, a);
      b_dev.upload(ctx, b);
      run_gemm(ctx, s, a_dev, b_dev, c_dev, "probe");
      const auto c = c_dev.download(ctx);
      const OperandViews x = operands_of(s, a, b);
      for (size_t i = 0; i < m; ++i) {
        for (size_t j = 0; j < n; ++j) {
          const auto [exact, magnitude] = exact_element(s, x, i, j);
          worst = std::max(worst, gemm_error_ratio(c[i * n + j], exact, magnitude, k));
        }
      }
    }
  }
  return worst;
}

// Worst error ratio of 64 elements of the product in `c_dev`, drawn with `rng`.
double sampled_error_ratio(ocl::Context& ctx, const GemmShape& s, const OperandViews& x,
                           const ocl::DeviceArray<float>& c_dev, std::mt19937& rng) {
  std::vector<float> c(s.m * s.n);
  c_dev.download(ctx, c.data(), c.size());
  double worst = 0.0;
  std::uniform_int_distribution<size_t> pick_i(0, s.m - 1), pick_j(0, s.n - 1);
  for (int sample = 0; sample < 64; ++sample) {
    const size_t i = pick_i(rng), j = pick_j(rng);
    const auto [exact, magnitude] = exact_element(s, x, i, j);
    worst = std::max(worst, gemm_error_ratio(c[i * s.n + j], exact, magnitude, s.k));
  }
  return worst;
}

std::vector<GemmShape> shapes_of(const Json& problems) {
  std::vector<GemmShape> shapes;
  for (const auto& p : problems) {
    shapes.push_back(gemm_shape(p.at("m").get<size_t>(), p.at("n").get<size_t>(), p.at("k").get<size_t>(),
                              p.at("ta").get<bool>(), p.at("tb").get<bool>()));
  }
  return shapes;
}

// Times each problem through mlp::gemm with the candidate installed (best of `reps` after a warm-up that
// compiles), and checks sampled elements of each result against a double dot product.
Json run_evaluate(ocl::Context& ctx, const Json& spec, const LogFn& log) {
  GemmTuning candidate;
  candidate.common = parameter_set_from_json(spec.at("set"));
  const double probe_ratio = probe_correctness(ctx, candidate.common);
  if (log)
    log(LogLevel::info, "  correctness probe (indirect kernel forced): worst error ratio " + text_of(probe_ratio));
  install_gemm_tuning(ctx, candidate);
  const int reps = spec.value("reps", 3);
  const std::vector<GemmShape> shapes = shapes_of(spec.at("problems"));
  size_t a_size = 0, b_size = 0, c_size = 0;
  for (const auto& s : shapes) {
    a_size = std::max(a_size, s.m * s.k);
    b_size = std::max(b_size, s.k * s.n);
    c_size = std::max(c_size, s.m * s.n);
  }
  std::mt19937 rng(5);
  const std::vector<float> a = random_values(a_size, rng), b = random_values(b_size, rng);
  ocl::DeviceArray<float> a_dev(ctx, a_size, "A"), b_dev(ctx, b_size, "B"), c_dev(ctx, c_size, "C");
  a_dev.upload(ctx, a);
  b_dev.upload(ctx, b);
  Json times = Json::array(), errors = Json::array();
  for (const auto& s : shapes) {
    run_gemm(ctx, s, a_dev, b_dev, c_dev, "tune");
    ctx.finish();
    errors.push_back(sampled_error_ratio(ctx, s, operands_of(s, a, b), c_dev, rng));
    double best = 1e30;
    for (int r = 0; r < reps; ++r) {
      const auto start = Clock::now();
      run_gemm(ctx, s, a_dev, b_dev, c_dev, "tune");
      ctx.finish();
      best = std::min(best, seconds_since(start));
    }
    times.push_back(best);
    if (log) {
      log(LogLevel::info, "  " + std::to_string(s.m) + "x" + std::to_string(s.n) + "x" + std::to_string(s.k) + " " +
                              gemm_kind_name(gemm_kind(s)) + ": " + text_of(2.0 * s.m * s.n * s.k / best * 1e-9) +
                              " GFLOP/s");
    }
  }
  return {{"seconds", times}, {"error_ratio", errors}, {"probe_error_ratio", probe_ratio}};
}

// ---- crossover: where the direct kernel should hand over to the indirect one ----

// Best of three timings of `s` (after a first call that builds the program) with every product forced
// through the indirect kernel (threshold 0) or the direct one (a threshold above any product).
double time_forced(ocl::Context& ctx, const ParameterSet& base, size_t threshold, const GemmShape& s,
                   const ocl::DeviceArray<float>& a, const ocl::DeviceArray<float>& b, ocl::DeviceArray<float>& c) {
  GemmTuning t;
  t.common = base;
  t.common["GemmRoutine"] = {{"XGEMM_MIN_INDIRECT_SIZE", threshold}};
  install_gemm_tuning(ctx, t);
  double best = 1e30;
  for (int rep = 0; rep < 4; ++rep) {
    const auto start = Clock::now();
    run_gemm(ctx, s, a, b, c, "crossover");
    ctx.finish();
    if (rep > 0) best = std::min(best, seconds_since(start));
  }
  return best;
}

// The forward product (rows × W · W × W) for each row count, indirect and direct, with the candidate's kernels.
Json run_crossover(ocl::Context& ctx, const Json& spec, const LogFn& log) {
  const ParameterSet base = parameter_set_from_json(spec.at("set"));
  const size_t width = spec.at("width");
  size_t max_rows = 0;
  for (const auto& r : spec.at("rows")) max_rows = std::max<size_t>(max_rows, r.get<size_t>());
  ocl::DeviceArray<float> a(ctx, max_rows * width, "A"), b(ctx, width * width, "B"), c(ctx, max_rows * width, "C");
  a.fill(ctx, 0.5f);
  b.fill(ctx, 0.25f);
  Json indirect = Json::array(), direct = Json::array();
  for (const auto& r : spec.at("rows")) {
    const GemmShape s = gemm_shape(r.get<size_t>(), width, width, false, false);
    indirect.push_back(time_forced(ctx, base, 0, s, a, b, c));
    direct.push_back(time_forced(ctx, base, size_t{1} << 20, s, a, b, c));
    if (log) {
      log(LogLevel::info, "  " + std::to_string(s.m) + " rows: indirect " +
                              text_of(indirect.back().get<double>() * 1e3) + " ms, direct " +
                              text_of(direct.back().get<double>() * 1e3) + " ms");
    }
  }
  return {{"indirect", indirect}, {"direct", direct}};
}

}  // namespace

Json kernel_tuner_step(const std::string& tuner, size_t m, size_t n, size_t k, double fraction) {
  return {{"type", "tuner"}, {"tuner", tuner}, {"m", m}, {"n", n}, {"k", k}, {"fraction", fraction}};
}

Json evaluate_step(const ParameterSet& set, const std::vector<GemmProblem>& problems, int reps) {
  Json shapes = Json::array();
  for (const auto& p : problems) {
    shapes.push_back({{"m", p.shape.m},
                      {"n", p.shape.n},
                      {"k", p.shape.k},
                      {"ta", p.shape.transpose_a},
                      {"tb", p.shape.transpose_b}});
  }
  return {{"type", "evaluate"}, {"set", parameter_set_json(set)}, {"problems", shapes}, {"reps", reps}};
}

Json crossover_step(const ParameterSet& set, size_t width, const std::vector<size_t>& rows) {
  return {{"type", "crossover"}, {"set", parameter_set_json(set)}, {"width", width}, {"rows", rows}};
}

Json run_tune_step(ocl::Context& ctx, const Json& spec, const LogFn& log) {
  const std::string type = spec.at("type");
  const auto start = Clock::now();
  Json result;
  if (type == "tuner") {
    result = run_kernel_tuner(ctx, spec, log);
  } else if (type == "evaluate") {
    result = run_evaluate(ctx, spec, log);
  } else if (type == "crossover") {
    result = run_crossover(ctx, spec, log);
  } else {
    throw Error("unknown tuning step '" + type + "' (expected tuner, evaluate or crossover)");
  }
  result["wall_seconds"] = seconds_since(start);
  return result;
}

double gemm_error_ratio(double computed, double exact, double magnitude, size_t k) {
  constexpr double kUnitRoundoff = 5.96e-8;  // float32, 2^-24 rounded
  const double error = std::abs(computed - exact);
  // The 1e-30 keeps an exact zero product (Σ|a·b| = 0) from dividing by zero.
  return std::isfinite(error) ? error / (2.0 * static_cast<double>(k) * kUnitRoundoff * magnitude + 1e-30) : 1e30;
}

Json parameter_set_json(const ParameterSet& set) {
  Json j = Json::object();
  for (const auto& [kernel, values] : set) j[kernel] = values;
  return j;
}

ParameterSet parameter_set_from_json(const Json& j) {
  ParameterSet set;
  for (const auto& [kernel, values] : j.items()) {
    for (const auto& [name, value] : values.items()) set[kernel][name] = value.get<size_t>();
  }
  return set;
}

}  // namespace mipnerf::gemm
