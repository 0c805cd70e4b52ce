// Timing a CPU GEMM library on one of the host MLP's products as the host MLP runs it: `threads` threads, each
// its own block's operands, the library held to the calling thread (host_mlp.cpp's run_blocks). What `tune`
// chooses a library per product by, and bench_gemm_libs's "ours" column.
#pragma once

#include <cstddef>
#include <functional>
#include <string>

#include "gemm/cpu_sgemm.hpp"

namespace mipnerf::gemm {

struct HostProductTiming {
  double gflops_best = 0, gflops_median = 0;  // all threads together, over `rounds` batches
  std::string skipped;  // why it was not timed: the library cannot run the shape, or computes something else
};

struct HostProductTimingSettings {
  int threads = 2;
  int rounds = 5;
  double batch_seconds = 0.05;  // each batch runs back-to-back calls for at least this long
};

// beta as the host MLP calls the product: weight gradients accumulate (1), the others overwrite (0). Checked first
// against `reference` on the same operands: the largest difference must stay within twice the float32 bound of a
// k-term dot product of values in [−1, 1] (2·k²·2⁻²⁴), else the library is skipped, with the difference.
HostProductTiming time_host_product(const CpuSgemmLibrary& library, const CpuSgemmLibrary& reference,
                                   const HostProductShape& shape, const HostProductTimingSettings& settings);

// Rates of `units_per_rep` per rep of body(thread, reps) on `threads` threads released together; the batch size
// doubles until a batch takes batch_seconds. Best and median over the rounds (also the bench's probes).
struct RateStats {
  double best = 0, median = 0;
};
RateStats measure_rate(int threads, double units_per_rep, int rounds, double batch_seconds,
                       const std::function<void(int thread, size_t reps)>& body);

}  // namespace mipnerf::gemm
