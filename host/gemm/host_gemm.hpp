// The host GEMM backend: a product of mlp::gemm run by the CPU BLAS (OpenBLAS cblas_sgemm) on the device buffers
// themselves, mapped into host memory (zero-copy on devices with unified memory, see cl/buffer.hpp).
//
// Queue ordering, which is what makes this safe next to the device's kernels on the same in-order queue:
//  1. every buffer the product touches is mapped (MappedBuffers::map: the maps enqueued, then one clFinish). The
//     queue is in order, so that returns only after every command enqueued before the maps (the kernels that wrote
//     A, B or C) and the maps themselves have finished;
//  2. cblas_sgemm runs on the host while the buffers are mapped; nothing else is enqueued meanwhile (one host
//     thread drives the queue, and this function returns only after step 3);
//  3. the buffers are unmapped with clEnqueueUnmapMemObject. Commands enqueued afterwards (the kernels that read
//     C) start only after the unmaps, again by queue order, so they see what the BLAS wrote.
// The price is a host synchronisation per product (the queue drains at each map); on a CPU device the kernels and
// the BLAS share the same cores, so there is nothing they could usefully overlap.
#pragma once

#include <string>

#include "cl/context.hpp"
#include "gemm/gemm.hpp"

namespace mipnerf::gemm {

// C = alpha · op(A) · op(B) + beta · C (GemmShape's conventions), finished when it returns. The views' sizes must
// have been checked (gemm() does). Throws mipnerf::Error when this build has no host BLAS or a map fails.
void host_gemm(ocl::Context& ctx, const GemmShape& shape, float alpha, const MatrixView& a, const MatrixView& b,
               float beta, const MatrixView& c, const std::string& what);

// Sets the host BLAS's thread count (no-op without a host BLAS), and reads it (1 without one).
void set_host_blas_threads(int threads);
int host_blas_threads();

}  // namespace mipnerf::gemm
