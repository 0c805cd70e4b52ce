// BLIS through its typed API (bli_sgemm), which takes a row and a column stride per operand, so a row-major
// operand is rs = ld, cs = 1 with no transposition trick. Its cblas layer is not used (OpenBLAS's names win there).
#include <blis.h>

#include "gemm/cpu_sgemm.hpp"

namespace mipnerf::gemm {

CpuSgemmLibrary blis_library() {
  CpuSgemmLibrary library;
  library.name = "blis";
  library.version = bli_info_get_version_str();
  library.threads = "OpenMP (Debian's blis-openmp); bli_thread_set_num_threads(1) keeps a call in its thread";
  library.sgemm = [](bool ta, bool tb, int m, int n, int k, const float* a, int lda, const float* b, int ldb,
                     float beta, float* c, int ldc) {
    float one = 1.0f;
    bli_sgemm(ta ? BLIS_TRANSPOSE : BLIS_NO_TRANSPOSE, tb ? BLIS_TRANSPOSE : BLIS_NO_TRANSPOSE, m, n, k, &one,
              const_cast<float*>(a), lda, 1, const_cast<float*>(b), ldb, 1, &beta, c, ldc, 1);
  };
  library.set_threads = [](int threads) { bli_thread_set_num_threads(threads); };
  return library;
}

}  // namespace mipnerf::gemm
