// bench_gemm_libs: the host MLP's matrix products at their real shapes through every CPU GEMM library this build
// found (OpenBLAS, BLIS, oneDNN, libxsmm), beside the machine's own limits measured in the same run
// (bench/machine_probe.hpp: the FMA peak, a STREAM triad, one large sgemm).
//
//   bench_gemm_libs [--presets quick,paper] [--rounds 5] [--batch-seconds 0.05] [--out FILE.json]
//
// Shapes: mlp::host_mlp_products of each preset's network at the host MLP's block (HostMlpOptions'
// target_block_rows = 256 rows, rounded down to whole rays): forward, backward data, backward weights, each with
// how often it occurs in one forward + backward. (The host MLP's backward of a network 256 wide runs twice as long
// blocks, mlp::backward_block_rows_for; this benchmark times every product at the forward's block.) Two thread arrangements per library:
//   ours     2 threads, each its own block's product, the library held to 1 thread per call: what host_mlp.cpp
//            does (run_blocks + SingleThreadedBlas);
//   library  1 product of 2 blocks' rows in one call, the library's own 2 threads.
// Every call is checked against OpenBLAS's result first (a library that computes something else, or cannot run the
// shape, is not timed: libxsmm 1.17 has no JIT kernel for the backward-data products).
// Each figure is the best and the median of `rounds` batches, each batch ≥ batch-seconds of back-to-back calls.
// Measured, never asserted; bench/studies/gemm_libs.py writes bench/results/gemm_libs_*.md from the JSON.
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

#include "bench/machine_probe.hpp"
#include "gemm/cpu_sgemm.hpp"
#include "gemm/cpu_sgemm_timing.hpp"
#include "gemm/gemm_tuning.hpp"
#include "mlp/host_mlp.hpp"
#include "mlp/mlp_products.hpp"
#include "train/config.hpp"
#include "train/model.hpp"

using namespace mipnerf;
using Clock = std::chrono::steady_clock;
using nlohmann::ordered_json;

namespace {

constexpr int kThreads = 2;
const size_t kBlockRows = mlp::HostMlpOptions{}.target_block_rows;  // the forward's blocks

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
  mlp::HostMlpOptions blocks;  // every product at the forward's block (see the top of this file)
  blocks.backward_target_block_rows = blocks.target_block_rows;
  ordered_json j;
  j["preset"] = preset;
  j["block_rows"] = mlp::forward_block_rows(blocks, samples);
  j["products"] = ordered_json::array();
  for (const mlp::HostMlpProduct& product : mlp::host_mlp_products(spec.mlps.front(), samples, blocks)) {
    ordered_json p;
    const gemm::HostProductShape& shape = product.shape;
    p["label"] = product.label;
    p["count"] = product.problem.count;
    p["gflop"] = product.problem.flops() * 1e-9;
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
    std::fprintf(stderr, "bench_gemm_libs: the machine's limits ...\n");
    bench::MachineProbeSettings probe;
    probe.threads = kThreads, probe.rounds = args.rounds, probe.batch_seconds = args.batch_seconds;
    const io::Json machine = bench::probe_machine(probe);
    out["machine"] = ordered_json::parse(machine.dump());
    out["presets"] = ordered_json::array();
    std::fprintf(stderr, "bench_gemm_libs: %s\n", bench::machine_summary(machine).c_str());
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
