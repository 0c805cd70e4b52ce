// oneDNN's dnnl_sgemm (row-major, its JIT AVX2/AVX-512 kernels). Debian builds oneDNN on OpenMP: a call uses
// omp_get_max_threads() of the calling thread, which omp_set_num_threads sets per thread.
#include <dnnl.h>
#include <omp.h>

#include <string>

#include "gemm/cpu_sgemm.hpp"

namespace mipnerf::gemm {

CpuSgemmLibrary onednn_library() {
  CpuSgemmLibrary library;
  library.name = "onednn";
  const dnnl_version_t* v = dnnl_version();
  library.version = std::to_string(v->major) + "." + std::to_string(v->minor) + "." + std::to_string(v->patch);
  library.threads = "OpenMP; omp_set_num_threads(1) in the calling thread keeps a call in it";
  library.sgemm = [](bool ta, bool tb, int m, int n, int k, const float* a, int lda, const float* b, int ldb,
                     float beta, float* c, int ldc) {
    dnnl_sgemm(ta ? 'T' : 'N', tb ? 'T' : 'N', m, n, k, 1.0f, a, lda, b, ldb, beta, c, ldc);
  };
  library.set_threads = [](int threads) { omp_set_num_threads(threads); };
  return library;
}

}  // namespace mipnerf::gemm
