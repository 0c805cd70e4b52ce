// bench_gemm_libs: the host MLP's matrix products at their real shapes through every CPU GEMM library this build
// found (OpenBLAS, BLIS, oneDNN, libxsmm), beside the machine's own limits measured in the same run: the FMA peak
// (a register-only loop of independent FMAs), the memory bandwidth (a STREAM-style triad) and one large sgemm.
//
//   bench_gemm_libs [--presets quick,paper] [--rounds 5] [--batch-seconds 0.05] [--out FILE.json]
//
// Shapes: mlp::mlp_gemm_problems of each preset's network at the host MLP's block (HostMlpOptions'
// target_block_rows = 256 rows, rounded down to whole rays): forward, backward data, backward weights, each with
// how often it occurs in one forward + backward. Two thread arrangements per library:
//   ours     2 threads, each its own block's product, the library held to 1 thread per call: what host_mlp.cpp
//            does (run_blocks + SingleThreadedBlas);
//   library  1 product of 2 blocks' rows in one call, the library's own 2 threads.
// Every call is checked against OpenBLAS's result first (a library that computes something else, or cannot run the
// shape, is not timed: libxsmm 1.17 has no JIT kernel for the backward-data products).
// Each figure is the best and the median of `rounds` batches, each batch ≥ batch-seconds of back-to-back calls.
// Measured, never asserted; bench/gemm_libs.py writes bench/results/gemm_libs_*.md from the JSON.
#include <immintrin.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "gemm/cpu_sgemm.hpp"
#include "gemm/cpu_sgemm_timing.hpp"
#include "gemm/gemm_tuning.hpp"
#include "mlp/mlp_products.hpp"
#include "train/config.hpp"
#include "train/model.hpp"

using namespace mipnerf;
using Clock = std::chrono::steady_clock;
using nlohmann::ordered_json;

namespace {

constexpr int kThreads = 2;
constexpr size_t kBlockRows = 256;  // HostMlpOptions::target_block_rows

struct Args {
  std::vector<std::string> presets{"quick", "paper"};
  int rounds = 5;
  double batch_seconds = 0.05;
  std::string out;
};

std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream stream(text);
  for (std::string part; std::getline(stream, part, ',');) {
    if (!part.empty()) parts.push_back(part);
  }
  return parts;
}

Args parse(int argc, char** argv) {
  Args args;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) throw std::runtime_error("bench_gemm_libs: " + flag + " needs a value");
    const std::string value = argv[++i];
    if (flag == "--presets") {
      args.presets = split(value);
    } else if (flag == "--rounds") {
      args.rounds = std::max(1, std::stoi(value));
    } else if (flag == "--batch-seconds") {
      args.batch_seconds = std::stod(value);
    } else if (flag == "--out") {
      args.out = value;
    } else {
      throw std::runtime_error("bench_gemm_libs: unknown flag " + flag +
                               " (known: --presets, --rounds, --batch-seconds, --out)");
    }
  }
  return args;
}

using Stats = gemm::RateStats;

ordered_json to_json(const Stats& s) { return {{"best", s.best}, {"median", s.median}}; }

template <typename Body>
Stats measure(int threads, double work_per_rep, const Args& args, const Body& body) {
  return gemm::measure_rate(threads, work_per_rep, args.rounds, args.batch_seconds, body);
}

// ---- the machine's limits ----

// 12 independent 8-wide FMA chains (enough to cover the FMA latency on two pipes), nothing from memory. Named
// variables, not an array: an array of __m256 is kept on the stack and every iteration would store and reload it.
__attribute__((target("avx2,fma"), noinline)) float fma_loop(size_t iterations) {
  __m256 a0 = _mm256_set1_ps(0.00f), a1 = _mm256_set1_ps(0.01f), a2 = _mm256_set1_ps(0.02f),
         a3 = _mm256_set1_ps(0.03f), a4 = _mm256_set1_ps(0.04f), a5 = _mm256_set1_ps(0.05f),
         a6 = _mm256_set1_ps(0.06f), a7 = _mm256_set1_ps(0.07f), a8 = _mm256_set1_ps(0.08f),
         a9 = _mm256_set1_ps(0.09f), a10 = _mm256_set1_ps(0.10f), a11 = _mm256_set1_ps(0.11f);
  const __m256 x = _mm256_set1_ps(0.999999f), y = _mm256_set1_ps(1e-7f);
  for (size_t it = 0; it < iterations; ++it) {
    a0 = _mm256_fmadd_ps(a0, x, y), a1 = _mm256_fmadd_ps(a1, x, y), a2 = _mm256_fmadd_ps(a2, x, y);
    a3 = _mm256_fmadd_ps(a3, x, y), a4 = _mm256_fmadd_ps(a4, x, y), a5 = _mm256_fmadd_ps(a5, x, y);
    a6 = _mm256_fmadd_ps(a6, x, y), a7 = _mm256_fmadd_ps(a7, x, y), a8 = _mm256_fmadd_ps(a8, x, y);
    a9 = _mm256_fmadd_ps(a9, x, y), a10 = _mm256_fmadd_ps(a10, x, y), a11 = _mm256_fmadd_ps(a11, x, y);
    // No instruction: the compiler must assume the chains changed, so it can neither fold them into a closed
    // form nor hoist a whole call out of the caller's loop.
    asm volatile("" : "+x"(a0), "+x"(a1), "+x"(a2), "+x"(a3), "+x"(a4), "+x"(a5), "+x"(a6), "+x"(a7), "+x"(a8),
                 "+x"(a9), "+x"(a10), "+x"(a11));
  }
  const __m256 sum = _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(a0, a1), _mm256_add_ps(a2, a3)),
                                   _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(a4, a5), _mm256_add_ps(a6, a7)),
                                                 _mm256_add_ps(_mm256_add_ps(a8, a9), _mm256_add_ps(a10, a11))));
  float out[8];
  _mm256_storeu_ps(out, sum);
  return out[0] + out[7];
}

ordered_json fma_peak(const Args& args) {
  if (!__builtin_cpu_supports("fma") || !__builtin_cpu_supports("avx2")) return {{"skipped", "no AVX2 + FMA"}};
  constexpr size_t kIterations = 1 << 16;
  const double flops = 2.0 * 8 * 12 * kIterations;
  volatile float sink = 0;
  auto body = [&](int, size_t reps) {
    float s = 0;
    for (size_t r = 0; r < reps; ++r) s += fma_loop(kIterations);
    sink = sink + s;
  };
  ordered_json j;
  j["what"] = "12 chains of 8-wide FMA (AVX2), GFLOP/s";
  j["threads_1"] = to_json(measure(1, flops * 1e-9, args, body));
  j["threads_2"] = to_json(measure(kThreads, flops * 1e-9, args, body));
  return j;
}

// STREAM's triad a = b + s·c on arrays far larger than the caches; bytes counted as STREAM does (3 arrays).
ordered_json stream_triad(const Args& args) {
  constexpr size_t kFloats = size_t{1} << 25;  // 128 MiB per array
  std::vector<float> a(kFloats, 0.0f), b(kFloats, 1.0f), c(kFloats, 2.0f);
  auto triad = [&](int threads) {
    return [&, threads](int t, size_t reps) {
      const size_t begin = kFloats * t / threads, end = kFloats * (t + 1) / threads;
      for (size_t r = 0; r < reps; ++r) {
        for (size_t i = begin; i < end; ++i) a[i] = b[i] + 0.5f * c[i];
      }
    };
  };
  const double gigabytes = 3.0 * sizeof(float) * kFloats * 1e-9;
  ordered_json j;
  j["what"] = "triad a = b + s*c, 3 x 128 MiB, GB/s (STREAM's byte count)";
  j["threads_1"] = to_json(measure(1, gigabytes, args, triad(1)));
  j["threads_2"] = to_json(measure(kThreads, gigabytes / kThreads, args, triad(kThreads)));
  return j;
}

// ---- the products ----

struct Operands {
  std::vector<float> a, b, c;
};

Operands operands_for(const gemm::HostProductShape& s, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Operands o{std::vector<float>(s.m * s.k), std::vector<float>(s.k * s.n), std::vector<float>(s.m * s.n, 0.0f)};
  for (float& x : o.a) x = u(rng);
  for (float& x : o.b) x = u(rng);
  return o;
}

// One library on one shape in both arrangements: ours (gemm::time_host_product, what tune measures) and the
// library's own threads on both blocks' rows in one call.
ordered_json time_product(const gemm::CpuSgemmLibrary& lib, const gemm::CpuSgemmLibrary& reference,
                          const gemm::HostProductShape& s, const Args& args) {
  const gemm::HostProductTiming ours =
      gemm::time_host_product(lib, reference, s, {kThreads, args.rounds, args.batch_seconds});
  if (!ours.skipped.empty()) return {{"skipped", ours.skipped}};
  ordered_json j;
  j["ours"] = {{"best", ours.gflops_best}, {"median", ours.gflops_median}};
  gemm::HostProductShape joined = s;  // the rows are m, or k for weight gradients
  (s.trans_a ? joined.k : joined.m) *= kThreads;
  Operands both = operands_for(joined, 13);
  const float beta = s.trans_a ? 1.0f : 0.0f;
  lib.set_threads(kThreads);
  j["library"] = to_json(measure(1, 2.0 * joined.m * joined.n * joined.k * 1e-9, args, [&](int, size_t reps) {
    for (size_t r = 0; r < reps; ++r) {
      lib.sgemm(joined.trans_a, joined.trans_b, int(joined.m), int(joined.n), int(joined.k), both.a.data(),
                int(joined.trans_a ? joined.m : joined.k), both.b.data(), int(joined.trans_b ? joined.k : joined.n),
                beta, both.c.data(), int(joined.n));
    }
  }));
  lib.set_threads(1);
  return j;
}


ordered_json bench_preset(const std::string& preset, const std::vector<gemm::CpuSgemmLibrary>& libraries,
                          const Args& args) {
  const train::TrainConfig config = train::resolve_config(preset, "mipnerf", {});
  const graph::GraphSpec spec = train::make_graph_spec(config, false);
  const size_t samples = static_cast<size_t>(config.num_samples);
  const size_t rows = std::max<size_t>(1, kBlockRows / samples) * samples;
  ordered_json j;
  j["preset"] = preset;
  j["block_rows"] = rows;
  j["products"] = ordered_json::array();
  for (const gemm::GemmProblem& problem : mlp::mlp_gemm_problems(spec.mlps.front(), rows)) {
    ordered_json p;
    const gemm::GemmShape& g = problem.shape;
    const gemm::HostProductShape shape{g.transpose_a, g.transpose_b, g.m, g.n, g.k};
    p["label"] = gemm::host_product_label(shape);
    p["count"] = problem.count;
    p["gflop"] = problem.flops() * 1e-9;
    for (const auto& lib : libraries) {
      p["libraries"][lib.name] = time_product(lib, libraries.front(), shape, args);
      if (p["libraries"][lib.name].contains("skipped")) {
        std::fprintf(stderr, "  %s %s: skipped: %s\n", preset.c_str(), lib.name.c_str(),
                     p["libraries"][lib.name]["skipped"].get<std::string>().c_str());
        continue;
      }
      std::fprintf(stderr, "  %-6s %-30s %-9s ours %6.1f (%6.1f)  library %6.1f (%6.1f) GFLOP/s\n", preset.c_str(),
                   p["label"].get<std::string>().c_str(), lib.name.c_str(),
                   p["libraries"][lib.name]["ours"]["best"].get<double>(),
                   p["libraries"][lib.name]["ours"]["median"].get<double>(),
                   p["libraries"][lib.name]["library"]["best"].get<double>(),
                   p["libraries"][lib.name]["library"]["median"].get<double>());
    }
    j["products"].push_back(p);
  }
  return j;
}

// One large sgemm (65,536 × 256 × 256) on the first library's 2 threads: the rate the products are held against.
ordered_json large_sgemm(const gemm::CpuSgemmLibrary& lib, const Args& args) {
  const gemm::HostProductShape s{false, false, 65536, 256, 256};
  Operands o = operands_for(s, 17);
  lib.set_threads(kThreads);
  const Stats stats = measure(1, 2.0 * s.m * s.n * s.k * 1e-9, args, [&](int, size_t reps) {
    for (size_t r = 0; r < reps; ++r) {
      lib.sgemm(false, false, int(s.m), int(s.n), int(s.k), o.a.data(), int(s.k), o.b.data(), int(s.n), 0.0f,
                o.c.data(), int(s.n));
    }
  });
  lib.set_threads(1);
  return {{"library", lib.name}, {"shape", "65536x256x256 forward, 2 threads"}, {"gflops", to_json(stats)}};
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Args args = parse(argc, argv);
    const std::vector<std::string> missing = gemm::cpu_sgemm_libraries_left_out();
    const auto& libraries = gemm::cpu_sgemm_libraries();
    for (const auto& line : missing) std::fprintf(stderr, "bench_gemm_libs: skipped %s\n", line.c_str());
    if (libraries.empty() || libraries.front().name != "openblas") {
      throw std::runtime_error("bench_gemm_libs: needs OpenBLAS (the reference every library is checked against)");
    }
    ordered_json out;
    out["host"]["threads"] = kThreads;
    out["host"]["hardware_threads"] = std::thread::hardware_concurrency();
    out["libraries"] = ordered_json::array();
    for (const auto& lib : libraries) out["libraries"].push_back({{"name", lib.name}, {"version", lib.version},
                                                                   {"threads", lib.threads}});
    out["missing"] = missing;
    std::fprintf(stderr, "bench_gemm_libs: FMA peak ...\n");
    out["fma_peak"] = fma_peak(args);
    std::fprintf(stderr, "bench_gemm_libs: stream triad ...\n");
    out["stream_triad"] = stream_triad(args);
    std::fprintf(stderr, "bench_gemm_libs: large sgemm ...\n");
    out["large_sgemm"] = large_sgemm(libraries.front(), args);
    out["presets"] = ordered_json::array();
    std::fprintf(stderr, "bench_gemm_libs: FMA peak %.1f GFLOP/s (2 threads), triad %.1f GB/s, large sgemm %.1f GFLOP/s\n", out["fma_peak"]["threads_2"]["best"].get<double>(), out["stream_triad"]["threads_2"]["best"].get<double>(), out["large_sgemm"]["gflops"]["best"].get<double>());
    for (const auto& preset : args.presets) out["presets"].push_back(bench_preset(preset, libraries, args));
    out["settings"] = {{"rounds", args.rounds}, {"batch_seconds", args.batch_seconds}, {"block_rows_target", kBlockRows}};
    const std::string text = out.dump(1);
    if (args.out.empty()) {
      std::cout << text << "\n";
    } else {
      std::ofstream(args.out) << text << "\n";
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
}
