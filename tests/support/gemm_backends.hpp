// The GEMM backends a test device supports, and a scope that runs a test's products on one of them.
#pragma once

#include <string>
#include <vector>

#include "cl/context.hpp"
#include "core/error.hpp"
#include "mlp/gemm_backend.hpp"
#include "support/skip.hpp"

namespace mipnerf::test {

// clblast always; host when the device shares host memory and the build has a host BLAS (what
// resolve_gemm_backend accepts), so a test loops over every backend the device can run. A build without a host BLAS
// marks the test skipped (a failure under CI): the host backend went untested.
inline std::vector<mlp::GemmBackend> supported_gemm_backends(const ocl::Context& ctx) {
  if (!mlp::host_blas_available()) {
    skip_test("this build has no host BLAS, so the host GEMM backend is not tested (install libopenblas-dev, "
              "reconfigure)");
  }
  std::vector<mlp::GemmBackend> out{mlp::GemmBackend::clblast};
  try {
    out.push_back(mlp::resolve_gemm_backend(mlp::GemmBackend::host, ctx.device_info(), mlp::host_blas_available()));
  } catch (const Error&) {
    // the device cannot run the host backend: CLBlast only
  }
  return out;
}

// Makes ctx's products run on `backend` until the scope ends, then puts back the backend it had.
class GemmBackendScope {
 public:
  GemmBackendScope(ocl::Context& ctx, mlp::GemmBackend backend) : ctx_(ctx), was_on_host_(ctx.gemm_on_host()) {
    mlp::use_gemm_backend(ctx, backend);
  }
  ~GemmBackendScope() { ctx_.set_gemm_on_host(was_on_host_); }
  GemmBackendScope(const GemmBackendScope&) = delete;
  GemmBackendScope& operator=(const GemmBackendScope&) = delete;

 private:
  ocl::Context& ctx_;
  bool was_on_host_;
};

}  // namespace mipnerf::test
