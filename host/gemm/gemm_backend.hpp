// Which library runs the MLP's products on a device, and the `gemm_backend` setting that chooses it: CLBlast (any
// device, the fallback) or the host's CPU BLAS working directly on the device buffers (mlp/host_gemm.hpp; only on
// devices whose buffers live in host memory, CL_DEVICE_HOST_UNIFIED_MEMORY).
#pragma once

#include <array>
#include <optional>
#include <vector>

#include "cl/context.hpp"
#include "core/enum_names.hpp"

namespace mipnerf::gemm {

enum class GemmBackend {
  automatic,  // the host BLAS on CPU devices that share host memory (when built in), CLBlast elsewhere
  clblast,    // CLBlast on the device, whatever the device
  host,       // the host BLAS on mapped device buffers; refused on devices with their own memory
};
constexpr std::array<EnumName<GemmBackend>, 3> enum_names(GemmBackend) {
  return {{{GemmBackend::automatic, "auto"}, {GemmBackend::clblast, "clblast"}, {GemmBackend::host, "host"}}};
}

// Every backend that runs products (each GemmBackend but `automatic`), in enum_names order: what tune measures for
// gemm_backend=auto (bench/backend_tuning.hpp) and what a new backend joins by its name alone.
std::vector<GemmBackend> gemm_backends();

// Whether this build links a host BLAS (OpenBLAS found when CMake configured it).
bool host_blas_available();

// What `wanted` means on `device` (never `automatic`). `automatic` is host on a CPU device with unified memory when
// `host_blas` is true, else clblast (the rule when tune has not measured the device). Throws mipnerf::Error when
// host is wanted on a device without unified memory or without a host BLAS, saying why and what to do.
GemmBackend resolve_gemm_backend(GemmBackend wanted, const ocl::DeviceInfo& device, bool host_blas);

// What `mipnerf-cl tune` measured for gemm_backend=auto on `device` (GemmTuning::auto_backend in the device's tuning
// file, when the file is for this device, driver and CLBlast and the backend is possible in this build); else
// nothing, and `log` hears why when the file could not be read.
std::optional<GemmBackend> measured_auto_backend(const ocl::DeviceInfo& device, const LogFn& log);

// What `wanted` means for ctx's device (auto: tune's measurement when there is one, else the rule above; never
// automatic), logged through the context. For the host backend it also sets the host BLAS's thread count to the
// device's compute units (see gemm_backend.cpp for why). mlp::make_network calls it: the backend belongs to the
// network that runs its products, not to the context.
GemmBackend choose_gemm_backend(ocl::Context& ctx, GemmBackend wanted);

}  // namespace mipnerf::gemm
