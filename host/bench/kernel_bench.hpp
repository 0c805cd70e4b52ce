// Throughput of every ray-math stage (rays … activations, forward and backward) on one OpenCL device, beside the
// double-precision CPU reference (host/ref, one thread) on the same inputs. Shared by `mipnerf-cl bench` and
// bench/bench_kernels.
//
// Inputs: a 800×800 Blender-like camera, R random pixels, then the pipeline's own outputs (one pass of rays,
// sampling, activations and rendering first), so every stage reads realistic values. Per stage: one untimed-but-
// recorded first call (PoCL generates a kernel's work-group code at its first launch), then `reps` calls, each
// followed by clFinish: wall time per call, launch overhead included as the host graph sees it.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "bench/timing.hpp"
#include "cl/context.hpp"

namespace mipnerf::bench {

struct KernelBenchOptions {
  size_t rays = 4096;         // R: the paper's batch
  size_t samples = 128;       // N: intervals per ray (the paper's per level)
  size_t reps = 10;           // timed device calls per stage, after the first call
  size_t reference_reps = 2;  // timed CPU reference calls per stage (best kept); 0 leaves the reference out
};

// One program's first clBuildProgram in this context (PoCL's on-disk cache may serve it: POCL_KERNEL_CACHE=0 gives
// a true cold compile).
struct ProgramBuild {
  std::string program;  // its kernel files, e.g. "gaussian.cl + encode.cl"
  double seconds = 0.0;
};

struct StageTiming {
  std::string stage;    // kernel and variant, e.g. "render_fwd (white)"
  std::string unit;     // what an item is: "rays", "edges", "intervals", "samples"
  size_t items = 0;     // items per call
  double first_call_seconds = 0.0;  // the first launch (work-group code generation on PoCL), then clFinish
  Timings device;                   // the `reps` timed calls after it
  double reference_seconds = 0.0;   // best CPU reference call; 0 when not measured
  double items_per_second() const { return device.best() > 0 ? static_cast<double>(items) / device.best() : 0.0; }
  double reference_items_per_second() const {
    return reference_seconds > 0 ? static_cast<double>(items) / reference_seconds : 0.0;
  }
};

struct KernelBenchResult {
  KernelBenchOptions options;
  std::vector<ProgramBuild> builds;  // in build order
  std::vector<StageTiming> stages;   // in pipeline order
};

// Builds every stage's program (timed), makes the inputs, and times each stage. `progress` is called before each
// stage with its name. Throws mipnerf::Error for zero sizes or device errors.
KernelBenchResult run_kernel_bench(ocl::Context& ctx, const KernelBenchOptions& options,
                                   const ProgressFn& progress = {});

}  // namespace mipnerf::bench
