// CPU reference of mlp::gemm: the same row-major convention, a plain triple loop.
#pragma once

#include <cstddef>

#include "gemm/gemm.hpp"

namespace mipnerf::ref {

// C[m×n] = alpha · op(A) · op(B) + beta · C (row-major, ld in elements), accumulated in double.
template <typename T>
void gemm(const gemm::GemmShape& s, double alpha, const T* a, size_t lda, const T* b, size_t ldb, double beta, T* c,
          size_t ldc) {
  for (size_t i = 0; i < s.m; ++i) {
    for (size_t j = 0; j < s.n; ++j) {
      double sum = 0.0;
      for (size_t p = 0; p < s.k; ++p) {
        const double a_ip = s.transpose_a ? a[p * lda + i] : a[i * lda + p];
        const double b_pj = s.transpose_b ? b[j * ldb + p] : b[p * ldb + j];
        sum += a_ip * b_pj;
      }
      // beta = 0 overwrites C without reading it (C may hold garbage), as BLAS does.
      const double old = beta == 0.0 ? 0.0 : beta * static_cast<double>(c[i * ldc + j]);
      c[i * ldc + j] = static_cast<T>(alpha * sum + old);
    }
  }
}

}  // namespace mipnerf::ref
