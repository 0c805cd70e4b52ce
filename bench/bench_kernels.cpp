// bench_kernels: throughput of each ray-math stage (rays … activations) on one OpenCL device, beside the
// double-precision CPU reference (host/ref, single thread) on the same inputs, in one run.
//
//   bench_kernels [--device SELECTOR] [--rays R] [--samples N] [--reps K] [--keep-cores-awake 0|1]
//
// SELECTOR is --device's rule (index or part of the name; MIPNERF_DEVICE is read when the flag is absent).
// Defaults are the paper's batch: R = 4096 rays, N = 128 samples per ray. Each stage is called once to warm up
// (the program was built before, timed separately as "first build"; PoCL's on-disk cache may serve it — run with
// POCL_KERNEL_CACHE=0 for a cold compile), then K timed calls, each followed by clFinish: wall time per call, so
// launch overhead is included as the host graph sees it. Throughput uses the best of the K calls (robust to other
// processes on a shared machine); the median is shown beside it. The CPU reference runs twice, best kept.
// --keep-cores-awake 1 is a diagnostic (bench/kernel_runtimes.py's "cores kept awake" column): one thread per CPU spins
// at SCHED_IDLE priority for the whole run, so no CPU goes idle and a runtime's sleeping worker threads wake without
// the latency of an idle (on a VM: halted) CPU; any runnable thread preempts the spinners at once. Linux only. Prints
// markdown. The measuring is host/bench/kernel_bench (shared with `mipnerf-cl bench`); this is its front-end.
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>
#include <vector>
#ifdef __linux__
#include <pthread.h>
#include <sched.h>
#endif
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

#include "bench/kernel_bench.hpp"
#include "cl/context.hpp"
#include "core/error.hpp"
#include "kernel_reference.hpp"

using namespace mipnerf;

namespace {

struct Args {
  std::string device;
  bench::KernelBenchOptions options;
  bool keep_cores_awake = false;
};

// One spinning thread per CPU at SCHED_IDLE until destroyed (--keep-cores-awake).
class CoreSpinners {
 public:
  CoreSpinners() {
#ifdef __linux__
    for (unsigned i = 0; i < std::max(1u, std::thread::hardware_concurrency()); ++i) {
      threads_.emplace_back([this] {
        const sched_param idle{};
        if (pthread_setschedparam(pthread_self(), SCHED_IDLE, &idle) != 0) failed_ = true;
        while (!stop_.load(std::memory_order_relaxed)) pause();
      });
    }
#else
    throw Error("bench_kernels: --keep-cores-awake needs Linux (SCHED_IDLE threads)");
#endif
  }
  ~CoreSpinners() {
    stop_ = true;
    for (auto& t : threads_) t.join();
  }
  bool failed() const { return failed_; }

 private:
  static void pause() {
#if defined(__x86_64__) || defined(__i386__)
    _mm_pause();
#else
    std::this_thread::yield();
#endif
  }
  std::atomic<bool> stop_{false}, failed_{false};
  std::vector<std::thread> threads_;
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
    } else if (flag == "--keep-cores-awake") {
      if (value != "0" && value != "1") throw Error("bench_kernels: --keep-cores-awake takes 0 or 1, not " + value);
      args.keep_cores_awake = value == "1";
    } else {
      throw Error("bench_kernels: unknown flag " + flag +
                  " (use --device, --rays, --samples, --reps, --keep-cores-awake)");
    }
  }
  return args;
}

void print_table(const ocl::DeviceInfo& info, const bench::KernelBenchResult& result, bool cores_kept_awake) {
  const auto& o = result.options;
  std::printf("## Ray-math kernels: %s\n\n", info.name.c_str());
  if (cores_kept_awake) std::printf("Cores kept awake: a SCHED_IDLE spinning thread per CPU during the run.\n\n");
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
  std::unique_ptr<CoreSpinners> spinners;
  if (args.keep_cores_awake) spinners = std::make_unique<CoreSpinners>();
  const auto result = bench::run_kernel_bench(ctx, args.options, {}, bench::reference_stages());
  if (spinners && spinners->failed()) throw Error("bench_kernels: could not give the spinning threads SCHED_IDLE");
  print_table(ctx.device_info(), result, args.keep_cores_awake);
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_kernels: %s\n", e.what());
  return 1;
}
