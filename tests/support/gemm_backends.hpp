// The GEMM backends a test device supports, and a scope that runs a test's products on one of them.
#pragma once

#include <string>
#include <vector>

#include "cl/context.hpp"
#include "core/error.hpp"
#include "gemm/gemm_backend.hpp"
#include "support/skip.hpp"

namespace mipnerf::test {

// Every backend of gemm::gemm_backends() that the device and the build can run (what resolve_gemm_backend accepts:
// clblast always; host when the device shares host memory and the build has a host BLAS), so a test loops over every
// backend the device can run, a new one included. A build without a host BLAS marks the test skipped (a failure under
// CI): the host backend went untested.
inline std::vector<gemm::GemmBackend> supported_gemm_backends(const ocl::Context& ctx) {
  if (!gemm::host_blas_available()) {
    skip_test("this build has no host BLAS, so the host GEMM backend is not tested (install libopenblas-dev, "
              "reconfigure)");
  }
  std::vector<gemm::GemmBackend> out;
  for (const gemm::GemmBackend backend : gemm::gemm_backends()) {
    try {
      out.push_back(gemm::resolve_gemm_backend(backend, ctx.device_info(), gemm::host_blas_available()));
    } catch (const Error&) {
      // the device cannot run this backend
    }
  }
  return out;
}

}  // namespace mipnerf::test
