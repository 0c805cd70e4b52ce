// Choosing the GEMM backend per device, and the host BLAS's thread count.
#include "gemm/gemm_backend.hpp"

#include <algorithm>
#include <string>

#include "core/error.hpp"
#include "gemm/gemm_tuning.hpp"
#include "gemm/host_gemm.hpp"

namespace mipnerf::gemm {

std::vector<GemmBackend> gemm_backends() {
  std::vector<GemmBackend> backends;
  for (const auto& entry : enum_names(GemmBackend{})) {
    if (entry.value != GemmBackend::automatic) backends.push_back(entry.value);
  }
  return backends;
}

bool host_blas_available() {
#ifdef MIPNERF_HAVE_OPENBLAS
  return true;
#else
  return false;
#endif
}

GemmBackend resolve_gemm_backend(GemmBackend wanted, const ocl::DeviceInfo& device, bool host_blas) {
  switch (wanted) {
    case GemmBackend::clblast:
      return GemmBackend::clblast;
    case GemmBackend::host:
      if (!device.host_unified_memory) {
        throw Error("gemm_backend=host: device '" + device.name +
                    "' has its own memory (CL_DEVICE_HOST_UNIFIED_MEMORY is false), so the host BLAS cannot work on "
                    "its buffers without copies; use gemm_backend=clblast or auto");
      }
      if (!host_blas) {
        throw Error(
            "gemm_backend=host: this build has no host BLAS; install libopenblas-dev and rebuild, or use "
            "gemm_backend=clblast");
      }
      return GemmBackend::host;
    case GemmBackend::automatic:
      // The rule when tune has not measured the device (measured_auto_backend): on a CPU device the kernels and the
      // host MLP share the same cores, and the host path beats CLBlast on PoCL at every network measured
      // (bench/results).
      return host_blas && device.host_unified_memory && (device.type & CL_DEVICE_TYPE_CPU) != 0 ? GemmBackend::host
                                                                                                : GemmBackend::clblast;
  }
  throw Error("internal error: gemm backend " + std::to_string(static_cast<int>(wanted)) + " has no rule");
}

std::optional<GemmBackend> measured_auto_backend(const ocl::DeviceInfo& device, const LogFn& log) {
  try {
    const std::optional<GemmTuning> tuning = read_tuning(tuning_file_path(device));
    if (!tuning || !tuning->auto_backend) return std::nullopt;
    if (!tuning_matches(*tuning, device)) return std::nullopt;  // load_gemm_tuning says so when it reads the file
    resolve_gemm_backend(*tuning->auto_backend, device, host_blas_available());  // still possible in this build?
    return tuning->auto_backend;
  } catch (const Error& e) {
    if (log) log(LogLevel::warning, std::string(e.what()) + "; gemm_backend=auto follows its rule");
    return std::nullopt;
  }
}

GemmBackend choose_gemm_backend(ocl::Context& ctx, GemmBackend wanted) {
  const LogFn log = [&ctx](LogLevel level, const std::string& message) { ctx.log(level, message); };
  const std::optional<GemmBackend> measured =
      wanted == GemmBackend::automatic ? measured_auto_backend(ctx.device_info(), log) : std::nullopt;
  const GemmBackend backend = resolve_gemm_backend(measured.value_or(wanted), ctx.device_info(), host_blas_available());
  if (backend == GemmBackend::host) {
    // Threads: the device's kernels (PoCL's pthread pool, one worker per compute unit) and the BLAS never run at the
    // same time, because every host product starts by mapping its buffers and draining the queue, and ends before the
    // next kernel is enqueued (host_gemm.hpp). So each may use every core while it runs: the BLAS gets as many
    // threads as the device has compute units (the cores PoCL was given), not more, so the two pools stay the same
    // size on the same cores. OpenBLAS's idle workers spin (sched_yield) for 2^OPENBLAS_THREAD_TIMEOUT cycles after
    // each call before they sleep; that variable is read when libopenblas is loaded, before main(), so only the
    // environment can lower it (docs/ARCHITECTURE.md, "GEMM backends").
    set_host_blas_threads(static_cast<int>(std::max<cl_uint>(1, ctx.device_info().compute_units)));
  }
  ctx.log(LogLevel::debug, std::string("GEMM backend: ") + enum_name(backend) + " on '" + ctx.device_info().name +
                              "' (gemm_backend=" + enum_name(wanted) +
                              (measured ? ", measured by tune: " + tuning_file_path(ctx.device_info()) : "") + ")");
  return backend;
}

}  // namespace mipnerf::gemm
