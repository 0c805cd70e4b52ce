// The machine's own limits, measured in a few seconds, so a stage's rate can be given as a fraction of what the
// machine can do rather than as a bare number: the FMA peak (a register-only loop of independent FMAs of the widest
// vectors the CPU runs: 8 floats with AVX2, 16 with AVX-512), the memory bandwidth (a STREAM-style triad on arrays
// far larger than the caches) and one large sgemm (65,536 × 256 × 256 on every CPU GEMM library built in, the
// fastest: the rate a well-shaped product reaches). `mipnerf-cl bench` and bench_gemm_libs report them.
#pragma once

#include "io/json.hpp"

namespace mipnerf::bench {

struct MachineProbeSettings {
  int threads = 2;               // the "all threads" figures (and the large sgemm's)
  int rounds = 3;                // best and median over these
  double batch_seconds = 0.05;   // each timed batch at least this long
  size_t triad_floats = size_t{1} << 24;  // per array (64 MiB: 3 arrays far beyond any cache)
};

// {"threads", "fma_peak_gflops": {"one_thread", "all_threads", "vector", "by_vector"}, "triad_gbs": {…},
// "large_sgemm_gflops": {"best", "median", "library", "shape", "by_library"}, "what"}; each figure {"best", "median"}.
// A part the machine cannot run (no AVX2 + FMA, no CPU GEMM library) is {"skipped": why}.
io::Json probe_machine(const MachineProbeSettings& settings);

// "FMA peak 198.7 GFLOP/s (2 threads, avx2_8_floats), triad 26.2 GB/s, large sgemm 121.6 GFLOP/s (openblas)" (best
// figures), or "" without.
std::string machine_summary(const io::Json& probe);

}  // namespace mipnerf::bench
