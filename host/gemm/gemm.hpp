// Row-major SGEMM on the device's buffers, through CLBlast or the host BLAS (gemm_backend.hpp): the matrix product
// of the networks (mlp/), the tuner and the benchmarks. The caller says which backend runs it.
#pragma once

#include <string>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "gemm/gemm_backend.hpp"

namespace mipnerf::gemm {

// C[m×n] = alpha · op(A) · op(B) + beta · C, all row-major. op(A) is m×k: A is stored m×k, or k×m
// when transpose_a. op(B) is k×n: B is stored k×n, or n×k when transpose_b.
struct GemmShape {
  bool transpose_a = false;
  bool transpose_b = false;
  size_t m = 0, n = 0, k = 0;
};

// GemmShape{transpose_a, transpose_b, m, n, k} written in the order people read a product: m×k times k×n.
inline GemmShape gemm_shape(size_t m, size_t n, size_t k, bool transpose_a = false, bool transpose_b = false) {
  return GemmShape{transpose_a, transpose_b, m, n, k};
}

// The products read and write ocl::MatrixView (cl/buffer.hpp); the names are kept here for the MLP.
using ocl::MatrixView;
using ocl::view;

// The product, in queue order, on `backend` (clblast or host; never automatic): CLBlast enqueues it (asynchronous);
// the host backend waits for the queue, computes it and unmaps before returning (gemm/host_gemm.hpp). `what` names
// the product in error messages (e.g. "layer 3 forward"). Sizes are checked against the buffers before either
// backend is called.
void sgemm(ocl::Context& ctx, GemmBackend backend, const GemmShape& shape, float alpha, const MatrixView& a,
           const MatrixView& b, float beta, const MatrixView& c, const std::string& what);

}  // namespace mipnerf::gemm
