// The GEMM backends a test device supports, and a scope that runs a test's products on one of them.
#pragma once

#include <string>
#include <vector>

#include "cl/context.hpp"
#include "core/error.hpp"
#include "gemm/gemm_backend.hpp"
#include "support/skip.hpp"

namespace mipnerf::test {

// clblast always; host when the device shares host memory and the build has a host BLAS (what
// resolve_gemm_backend accepts), so a test loops over every backend the device can run. A build without a host BLAS
// marks the test skipped (a failure under CI): the host backend went untested.
inline std::vector<gemm::GemmBackend> supported_gemm_backends(const ocl::Context& ctx) {
  if (!gemm::host_blas_available()) {
    skip_test("this build has no host BLAS, so the host GEMM backend is not tested (install libopenblas-dev, "
              "reconfigure)");
  }
  std::vector<gemm::GemmBackend> out{gemm::GemmBackend::clblast};
  try {
    out.push_back(gemm::resolve_gemm_backend(gemm::GemmBackend::host, ctx.device_info(), gemm::host_blas_available()));
  } catch (const Error&) {
    // the device cannot run the host backend: CLBlast only
  }
  return out;
}

}  // namespace mipnerf::test
