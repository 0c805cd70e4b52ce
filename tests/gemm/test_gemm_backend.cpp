// Choosing the GEMM backend: the rule for each device kind, the refusals and their messages, the setting's names.
#include <doctest/doctest.h>

#include <algorithm>
#include <vector>

#include "core/error.hpp"
#include "gemm/gemm_backend.hpp"

using namespace mipnerf;
using gemm::GemmBackend;

namespace {

// A device as list_devices() would describe it; no OpenCL device behind it (the decision reads only these fields).
ocl::DeviceInfo fake_device(cl_device_type type, bool unified) {
  ocl::DeviceInfo d;
  d.name = type == CL_DEVICE_TYPE_GPU ? "Fake GPU" : "Fake CPU";
  d.type = type;
  d.host_unified_memory = unified;
  d.compute_units = 2;
  return d;
}

}  // namespace

TEST_CASE("gemm backend: host is refused on a device with its own memory, saying why and what to do") {
  const auto gpu = fake_device(CL_DEVICE_TYPE_GPU, false);
  CHECK_THROWS_WITH_AS(gemm::resolve_gemm_backend(GemmBackend::host, gpu, true),
                       doctest::Contains("'Fake GPU' has its own memory (CL_DEVICE_HOST_UNIFIED_MEMORY is false)"),
                       Error);
  CHECK_THROWS_WITH_AS(gemm::resolve_gemm_backend(GemmBackend::host, gpu, true),
                       doctest::Contains("use gemm_backend=clblast or auto"), Error);
}

TEST_CASE("gemm backend: host is refused without a host BLAS, naming the package") {
  CHECK_THROWS_WITH_AS(gemm::resolve_gemm_backend(GemmBackend::host, fake_device(CL_DEVICE_TYPE_CPU, true), false),
                       doctest::Contains("libopenblas-dev"), Error);
}

TEST_CASE("gemm backend: auto picks the host BLAS only on CPU devices that share host memory") {
  const auto cpu = fake_device(CL_DEVICE_TYPE_CPU, true);
  CHECK(gemm::resolve_gemm_backend(GemmBackend::automatic, cpu, true) == GemmBackend::host);
  CHECK(gemm::resolve_gemm_backend(GemmBackend::automatic, cpu, false) == GemmBackend::clblast);
  // An integrated GPU shares host memory but runs its own kernels faster than the host's cores: CLBlast.
  CHECK(gemm::resolve_gemm_backend(GemmBackend::automatic, fake_device(CL_DEVICE_TYPE_GPU, true), true) ==
        GemmBackend::clblast);
  CHECK(gemm::resolve_gemm_backend(GemmBackend::automatic, fake_device(CL_DEVICE_TYPE_GPU, false), true) ==
        GemmBackend::clblast);
  CHECK(gemm::resolve_gemm_backend(GemmBackend::automatic, fake_device(CL_DEVICE_TYPE_CPU, false), true) ==
        GemmBackend::clblast);
}

TEST_CASE("gemm backend: clblast is taken on every device, and host where it is allowed") {
  for (const bool unified : {false, true}) {
    CHECK(gemm::resolve_gemm_backend(GemmBackend::clblast, fake_device(CL_DEVICE_TYPE_GPU, unified), false) ==
          GemmBackend::clblast);
  }
  CHECK(gemm::resolve_gemm_backend(GemmBackend::host, fake_device(CL_DEVICE_TYPE_CPU, true), true) == GemmBackend::host);
}

TEST_CASE("gemm backend: the setting's names") {
  CHECK(enum_choices<GemmBackend>() == "auto | clblast | host");
  CHECK(enum_from_name<GemmBackend>("auto") == GemmBackend::automatic);
  CHECK(enum_from_name<GemmBackend>("host") == GemmBackend::host);
  CHECK_FALSE(enum_from_name<GemmBackend>("openblas").has_value());
}

TEST_CASE("gemm backend: the list of backends is every setting but auto, each once") {
  const std::vector<GemmBackend> backends = gemm::gemm_backends();
  CHECK(backends.size() + 1 == enum_names(GemmBackend{}).size());
  for (const auto& entry : enum_names(GemmBackend{})) {
    const auto count = std::count(backends.begin(), backends.end(), entry.value);
    CHECK_MESSAGE(count == (entry.value == GemmBackend::automatic ? 0 : 1), entry.name);
  }
}
