// Throughput of every ray-math stage (rays … activations, forward and backward) on one OpenCL device, and, when a
// CPU implementation of the stages is handed in, beside it on the same inputs. The stages, their kernels and the
// options they run with come from the one stage list (host/ops/stage_list.hpp) that the specialisation test walks
// too. Shared by `mipnerf-cl bench` (device only) and bench/bench_kernels (beside the double-precision reference,
// bench/reference/kernel_reference: the library does not link the reference, the test oracle).
//
// Inputs: a 800×800 Blender-like camera, R random pixels, then the pipeline's own outputs (one pass of rays,
// sampling, activations and rendering first), so every stage reads realistic values. Per stage: one untimed-but-
// recorded first call (PoCL generates a kernel's work-group code at its first launch), then `reps` calls, each
// followed by clFinish: wall time per call, launch overhead included as the host graph sees it.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "bench/timing.hpp"
#include "cl/context.hpp"
#include "core/stage_options.hpp"
#include "ops/stage_list.hpp"

namespace mipnerf::bench {

struct KernelBenchOptions {
  size_t rays = 4096;         // R: the paper's batch
  size_t samples = 128;       // N: intervals per ray (the paper's per level)
  size_t reps = 10;           // timed device calls per stage, after the first call
  size_t reference_reps = 2;  // timed CPU reference calls per stage (best kept); 0 leaves the reference out
};

// The device's inputs after one pass of the pipeline, in double, for a CPU implementation of the stages; o1…o7 are
// its scratch outputs (discarded). Layouts as the device buffers (docs/ARCHITECTURE.md, "Buffers and layouts").
struct KernelBenchInputs {
  std::vector<double> cameras, origins, directions, radii, near, far, viewdirs, t_edges, weights;
  std::vector<double> raw_density, raw_rgb, density, rgb, d_comp, means, covs;
  std::vector<uint32_t> camera_ids, pixel_ids;
  std::vector<double> o1, o2, o3, o4, o5, o6, o7;
};

// Given a listed kernel (ops::StageKernel::id), the call that runs it on the CPU over `inputs` (R rays × N samples)
// with `options` (the benchmark's: the default ops::RayMathOptions). Implementations map every id with a switch, so
// a kernel added to the stage list without its reference does not compile.
using ReferenceStages =
    std::function<std::function<void()>(ops::KernelId kernel, const ops::RayMathOptions& options,
                                        KernelBenchInputs& inputs, size_t R, size_t N, const RngKey& key)>;

// One program's first clBuildProgram in this context (PoCL's on-disk cache may serve it: POCL_KERNEL_CACHE=0 gives
// a true cold compile).
struct ProgramBuild {
  std::string program;  // its kernel files, e.g. "gaussian.cl + encode.cl" (ops::StageDescription::program)
  double seconds = 0.0;
};

struct StageTiming {
  std::string stage;    // kernel and setting, e.g. "render_fwd (white)" (ops::StageKernel::row())
  std::string unit;     // what an item is: "rays", "edges", "intervals", "samples" (ops::unit_name)
  size_t items = 0;     // items per call
  double first_call_seconds = 0.0;  // the first launch (work-group code generation on PoCL), then clFinish
  Timings device;                   // the `reps` timed calls after it
  double reference_seconds = 0.0;   // best CPU reference call; 0 when not measured (no ReferenceStages given)
  double items_per_second() const { return device.best() > 0 ? static_cast<double>(items) / device.best() : 0.0; }
  double reference_items_per_second() const {
    return reference_seconds > 0 ? static_cast<double>(items) / reference_seconds : 0.0;
  }
};

struct KernelBenchResult {
  KernelBenchOptions options;
  std::vector<ProgramBuild> builds;  // one per stage of ops::ray_math_stages(), in its order
  std::vector<StageTiming> stages;   // one per kernel of those stages, in their order
};

// Builds every stage's program (timed), makes the inputs, and times each stage, and `reference`'s version of it when
// given (else reference_reps is recorded as 0). `progress` is called before each stage with its name. Throws
// mipnerf::Error for zero sizes, device errors, or a listed stage or kernel this benchmark cannot run.
KernelBenchResult run_kernel_bench(ocl::Context& ctx, const KernelBenchOptions& options,
                                   const ProgressFn& progress = {}, const ReferenceStages& reference = {});

}  // namespace mipnerf::bench
