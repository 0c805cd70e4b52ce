// bench_kernels: throughput of each ray-math stage (rays … activations) on one OpenCL device, beside the
// double-precision CPU reference (host/ref, single thread) on the same inputs, in one run.
//
//   bench_kernels [--device SELECTOR] [--rays R] [--samples N] [--reps K]
//
// SELECTOR is --device's rule (index or part of the name; MIPNERF_DEVICE is read when the flag is absent).
// Defaults are the paper's batch: R = 4096 rays, N = 128 samples per ray. Each stage is called once to warm up
// (the program was built before, timed separately as "first build"; PoCL's on-disk cache may serve it — run with
// POCL_KERNEL_CACHE=0 for a cold compile), then K timed calls, each followed by clFinish: wall time per call, so
// launch overhead is included as the host graph sees it. Throughput uses the best of the K calls (robust to other
// processes on a shared machine); the median is shown beside it. The CPU reference runs twice, best kept.
// Prints markdown. The measuring is host/bench/kernel_bench (shared with `mipnerf-cl bench`); this is its front-end.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "bench/kernel_bench.hpp"
#include "kernel_reference.hpp"
#include "cl/context.hpp"
#include "core/error.hpp"

using namespace mipnerf;

namespace {

struct Args {
  std::string device;
  bench::KernelBenchOptions options;
};

Args parse(int argc, char** argv) {
  Args args;
  if (const char* env = std::getenv("MIPNERF_DEVICE")) args.device = env;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) throw Error("bench_kernels: " + flag + " needs a value");
    const std::string value = argv[++i];
    if (flag == "--device") {
      args.device = value;
    } else if (flag == "--rays") {
      args.options.rays = std::stoul(value);
    } else if (flag == "--samples") {
      args.options.samples = std::stoul(value);
    } else if (flag == "--reps") {
      args.options.reps = std::max<size_t>(1, std::stoul(value));
    } else {
      throw Error("bench_kernels: unknown flag " + flag + " (use --device, --rays, --samples, --reps)");
    }
  }
  return args;
}

void print_table(const ocl::DeviceInfo& info, const bench::KernelBenchResult& result) {
  const auto& o = result.options;
  std::printf("## Ray-math kernels: %s\n\n", info.name.c_str());
  std::printf(
      "Device: %s (%s, %s), %u compute units. Batch: %zu rays x %zu samples. Device: best and median of %zu "
      "calls after a warm-up, wall time with clFinish; items/s from the best. CPU reference: host/ref in "
      "double, one thread, best of %zu calls.\n\n",
      info.name.c_str(), info.platform_name.c_str(), info.type_name().c_str(), info.compute_units, o.rays, o.samples,
      o.reps, o.reference_reps);
  std::printf(
      "| stage | items | device ms best (median) | device items/s | CPU ref ms | CPU ref items/s | "
      "device / ref |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& s : result.stages) {
    std::printf("| %s | %zu %s | %.3f (%.3f) | %.3g | %.1f | %.3g | %.1fx |\n", s.stage.c_str(), s.items,
                s.unit.c_str(), 1e3 * s.device.best(), 1e3 * s.device.median(), s.items_per_second(),
                1e3 * s.reference_seconds, s.reference_items_per_second(), s.reference_seconds / s.device.best());
  }
  std::printf(
      "\nFirst build of each program: clBuildProgram, served from PoCL's on-disk cache when it holds the program "
      "(POCL_KERNEL_CACHE=0 for a cold compile); PoCL generates each kernel's work-group code at its first "
      "launch, which the warm-up call absorbs.\n\n");
  std::printf("| program | first build s |\n|---|---:|\n");
  for (const auto& b : result.builds) std::printf("| %s | %.2f |\n", b.program.c_str(), b.seconds);
}

}  // namespace

int main(int argc, char** argv) try {
  const Args args = parse(argc, argv);
  auto devices = ocl::list_devices();
  ocl::Context ctx(ocl::choose_device(devices, args.device));
  print_table(ctx.device_info(), bench::run_kernel_bench(ctx, args.options, {}, bench::reference_stages()));
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_kernels: %s\n", e.what());
  return 1;
}
