// The host GEMM backend: map (then wait for the queue), cblas_sgemm, unmap. See host_gemm.hpp for the queue ordering.
#include "gemm/host_gemm.hpp"

#include "cl/error.hpp"
#include "core/error.hpp"
#include "gemm/mapped_buffers.hpp"

#ifdef MIPNERF_HAVE_OPENBLAS
#include <cblas.h>
#endif

namespace mipnerf::gemm {

#ifdef MIPNERF_HAVE_OPENBLAS

void host_gemm(ocl::Context& ctx, const GemmShape& s, float alpha, const MatrixView& a, const MatrixView& b, float beta,
               const MatrixView& c, const std::string& what) {
  MappedBuffers mapped(ctx, "host gemm(" + what + ")");
  mapped.need(a, false);
  mapped.need(b, false);
  mapped.need(c, true);
  mapped.map();  // from here until `mapped` is destroyed, no device command touches these buffers
  const ocl::HostTimer timer(ctx);  // the product alone: the map's wait is the previous commands' time
  cblas_sgemm(CblasRowMajor, s.transpose_a ? CblasTrans : CblasNoTrans, s.transpose_b ? CblasTrans : CblasNoTrans,
              static_cast<int>(s.m), static_cast<int>(s.n), static_cast<int>(s.k), alpha, mapped.at(a),
              static_cast<int>(a.ld), mapped.at(b), static_cast<int>(b.ld), beta, mapped.at(c), static_cast<int>(c.ld));
}

void set_host_blas_threads(int threads) { openblas_set_num_threads(threads); }

int host_blas_threads() { return openblas_get_num_threads(); }

#else

void host_gemm(ocl::Context&, const GemmShape&, float, const MatrixView&, const MatrixView&, float, const MatrixView&,
               const std::string& what) {
  throw Error("gemm(" + what +
              "): this build has no host BLAS; install libopenblas-dev and rebuild, or use "
              "gemm_backend=clblast");
}

void set_host_blas_threads(int) {}

int host_blas_threads() { return 1; }

#endif

}  // namespace mipnerf::gemm
