// OpenBLAS's cblas_sgemm: what the host MLP calls today (one OpenBLAS thread per call, our threads split the rows).
#include <cblas.h>

#include "gemm/cpu_sgemm.hpp"

namespace mipnerf::gemm {

CpuSgemmLibrary openblas_library() {
  CpuSgemmLibrary library;
  library.name = "openblas";
  library.version = openblas_get_config();
  library.threads = "pthreads; openblas_set_num_threads(1) keeps a call in its thread";
  library.sgemm = [](bool ta, bool tb, int m, int n, int k, const float* a, int lda, const float* b, int ldb,
                     float beta, float* c, int ldc) {
    cblas_sgemm(CblasRowMajor, ta ? CblasTrans : CblasNoTrans, tb ? CblasTrans : CblasNoTrans, m, n, k, 1.0f, a, lda,
                b, ldb, beta, c, ldc);
  };
  library.set_threads = [](int threads) { openblas_set_num_threads(threads); };
  return library;
}

}  // namespace mipnerf::gemm
