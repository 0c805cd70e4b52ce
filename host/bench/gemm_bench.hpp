// GFLOP/s of the MLP's matrix products through CLBlast with a given parameter set installed (CLBlast's defaults, or
// a file `mipnerf-cl tune` wrote), optionally beside a host BLAS the caller supplies (bench/bench_gemm: OpenBLAS),
// and the paper's whole network on one chunk. Shared by `mipnerf-cl bench` and bench/bench_gemm.
//
// Products (row-major) for each width W at R rows: forward Y = X·W (R×W·W×W), backward data dX = dY·Wᵀ, backward
// weights dW = Xᵀ·dY (W×R·R×W). Per configuration and product: the first call timed on its own in the first round
// (CLBlast builds its program for a parameter set then; PoCL's on-disk cache may serve the compile), then one
// warm-up call (device configurations: after a parameter switch) and `reps` timed calls, each followed by clFinish.
// The whole sequence over the configurations runs `rounds` times, so a noisy moment on a shared machine hits every
// configuration alike.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "bench/timing.hpp"
#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "gemm/gemm.hpp"
#include "gemm/gemm_tuning.hpp"
#include "mlp/network.hpp"

namespace mipnerf::bench {

struct GemmProduct {
  std::string kind;  // "forward", "backward data", "backward weights"
  gemm::GemmShape shape;
  double flops() const { return 2.0 * static_cast<double>(shape.m) * shape.n * shape.k; }
  std::string label() const;   // "forward 65536x256x256"
  std::string layout() const;  // "A·B", "A·Bᵀ" or "Aᵀ·B"
};

// For each width, in order: forward, backward data, backward weights at `rows` rows.
std::vector<GemmProduct> mlp_products(const std::vector<size_t>& widths, size_t rows);

// Random operands in [−1, 1] for every product of a list (sized for the largest), on the host and on the device.
struct GemmOperands {
  GemmOperands(ocl::Context& ctx, const std::vector<GemmProduct>& products);
  std::vector<float> a, b, c;
  ocl::DeviceArray<float> a_device, b_device, c_device;
};

// Wall seconds of one product on `backend` (gemm::sgemm; CLBlast with whatever parameters are installed), clFinish
// included.
double time_gemm(ocl::Context& ctx, gemm::GemmBackend backend, GemmOperands& operands, const GemmProduct& product);

// A configuration to time. Device: CLBlast with `tuning` installed, or with its defaults when there is none. Host:
// `host_call` set (e.g. OpenBLAS on operands.a/b/c), returning the wall seconds of one product; no warm-up call.
struct GemmConfig {
  std::string name;  // "CLBlast default", "CLBlast tuned", "OpenBLAS"
  std::optional<gemm::GemmTuning> tuning;
  std::function<double(const GemmProduct&, GemmOperands&)> host_call;
  bool on_host() const { return static_cast<bool>(host_call); }
};

struct GemmSeries {
  std::string name;
  std::vector<double> first_call_seconds;  // per product, its first call in round 1 (cold for its parameter set)
  std::vector<Timings> calls;              // per product, every timed call of every round
  double gflops_best(const GemmProduct& p, size_t i) const;
  double gflops_median(const GemmProduct& p, size_t i) const;
};

struct GemmBenchOptions {
  std::vector<size_t> widths = {64, 128, 256};
  size_t rows = 65536;
  size_t reps = 5;    // timed calls per product, configuration and round
  size_t rounds = 2;  // passes over every configuration
};

struct GemmBenchResult {
  GemmBenchOptions options;
  std::vector<GemmProduct> products;
  std::vector<GemmSeries> series;  // one per configuration, in the order given
};

// Times every product with every configuration. Leaves CLBlast's defaults installed afterwards: a caller that wants
// its tuning for later work installs it again (a CLBlast network made afterwards loads the device's file itself:
// gemm::prepare_clblast_tuning).
// `progress` is called after each (round, configuration, product) with a label and the latest figure.
GemmBenchResult run_gemm_bench(ocl::Context& ctx, const GemmBenchOptions& options,
                               const std::vector<GemmConfig>& configs, const ProgressFn& progress = {});

// The device configurations for a device: CLBlast's defaults, then the tuned file when `tuning` holds one.
std::vector<GemmConfig> clblast_configs(const std::optional<gemm::GemmTuning>& tuning);

// The host GEMM backend (mlp::gemm with gemm_backend=host: maps of the device buffers, a clFinish, the CPU BLAS,
// unmaps, clFinish), as a configuration beside CLBlast's; nothing when ctx's device cannot run it. Each timed call
// switches ctx to the host backend and back, so the other configurations keep CLBlast. ctx must outlive the result.
std::optional<GemmConfig> host_backend_config(ocl::Context& ctx);

// The whole network on one chunk of rays × samples rows, with whatever GEMM parameters are installed: best of `reps`
// (after one untimed pass that builds the programs) training forward, backward, and inference forward, each
// followed by clFinish. Seconds.
struct MlpChunkTimes {
  size_t rows = 0;
  double forward = 0, backward = 0, inference = 0;
  double training_rows_per_second() const { return rows / (forward + backward); }
};
MlpChunkTimes time_mlp_chunk(ocl::Context& ctx, mlp::Network& net, size_t rays, size_t samples, size_t reps);

// Forgets every program CLBlast compiled in this process (clblast::ClearCache), so the next first call of each
// parameter set builds it again (PoCL's on-disk cache aside): what a fresh process would pay.
void clear_clblast_programs();

}  // namespace mipnerf::bench
