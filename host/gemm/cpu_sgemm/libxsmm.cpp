// libxsmm's JIT-generated kernels (libxsmm_smmdispatch), one per shape, cached here. libxsmm is column-major: the
// row-major C = op(A)·op(B) is the column-major Cᵀ = op(B)ᵀ·op(A)ᵀ, so the operands swap (B first) and so do the
// transposition flags. A shape libxsmm cannot JIT (1.17: a transposed A', i.e. our backward-data products) throws
// rather than falling back to a BLAS, which would time OpenBLAS again under libxsmm's name: tune and the bench
// skip libxsmm for such shapes (every_shape = false).
#include <libxsmm.h>

#include <map>
#include <mutex>
#include <string>
#include <tuple>

#include "core/error.hpp"
#include "gemm/cpu_sgemm.hpp"

namespace mipnerf::gemm {
namespace {

using Key = std::tuple<bool, bool, int, int, int, int, int, int, float>;

libxsmm_smmfunction kernel_for(bool ta, bool tb, int m, int n, int k, int lda, int ldb, int ldc, float beta) {
  static std::mutex mutex;
  static std::map<Key, libxsmm_smmfunction> kernels;
  const std::lock_guard<std::mutex> lock(mutex);
  const Key key{ta, tb, m, n, k, lda, ldb, ldc, beta};
  auto found = kernels.find(key);
  if (found != kernels.end()) return found->second;
  // Column-major: M' = n, N' = m, K' = k; A' = B (transposed when tb), B' = A (transposed when ta).
  const libxsmm_blasint cm = n, cn = m, ck = k, clda = ldb, cldb = lda, cldc = ldc;
  const int flags = (tb ? LIBXSMM_GEMM_FLAG_TRANS_A : 0) | (ta ? LIBXSMM_GEMM_FLAG_TRANS_B : 0);
  const float alpha = 1.0f;
  libxsmm_smmfunction kernel =
      libxsmm_smmdispatch(cm, cn, ck, &clda, &cldb, &cldc, &alpha, &beta, &flags, nullptr);
  if (kernel == nullptr) {
    throw Error("libxsmm: no JIT kernel for this shape (m=" + std::to_string(m) + " n=" +
                             std::to_string(n) + " k=" + std::to_string(k) + (ta ? " Aᵀ" : "") + (tb ? " Bᵀ" : "") +
                             ")");
  }
  kernels.emplace(key, kernel);
  return kernel;
}

}  // namespace

CpuSgemmLibrary libxsmm_library() {
  libxsmm_init();
  CpuSgemmLibrary library;
  library.name = "libxsmm";
  library.version = LIBXSMM_VERSION;
  library.threads = "none inside a kernel: each call runs in the calling thread";
  library.sgemm = [](bool ta, bool tb, int m, int n, int k, const float* a, int lda, const float* b, int ldb,
                     float beta, float* c, int ldc) {
    kernel_for(ta, tb, m, n, k, lda, ldb, ldc, beta)(b, a, c);
  };
  library.set_threads = [](int) {};
  library.every_shape = false;
  return library;
}

}  // namespace mipnerf::gemm
