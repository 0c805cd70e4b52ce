// Host wrapper of kernels/dilate.cl: mip-NeRF 360's max-dilation of a proposal histogram before the next round samples
// from it (multinerf stepfun.max_dilate_weights, renormalised, [1:-1] kept). No backward: sampling is a constant.
#pragma once

#include <cstddef>
#include <cstdint>

#include "cl/buffer.hpp"
#include "cl/context.hpp"

namespace mipnerf::ops {

// Edges the dilation of an N-interval histogram gives (3N − 1), and its weights (3N − 2).
inline size_t dilated_edges(size_t n_intervals) { return 3 * n_intervals - 1; }
inline size_t dilated_intervals(size_t n_intervals) { return 3 * n_intervals - 2; }

class MaxDilate {
 public:
  explicit MaxDilate(ocl::Context& ctx);

  // Enqueues max_dilate_weights_fwd: (s_edges [R][N+1], weights [R][N]) dilated by `dilation` (normalised s, ≥ 0)
  // within [0, 1] → s_out [R][3N−1], w_out [R][3N−2]; `scratch` [R][N] holds each ray's sliding-window deque. Throws
  // mipnerf::Error for a buffer too small, N = 0 or a dilation that is negative or not finite.
  void fwd(const ocl::DeviceArray<float>& s_edges, const ocl::DeviceArray<float>& weights, size_t n_rays,
           size_t n_intervals, float dilation, ocl::DeviceArray<float>& s_out, ocl::DeviceArray<float>& w_out,
           ocl::DeviceArray<uint32_t>& scratch);

 private:
  ocl::Context* ctx_;
  ::cl::Kernel* fwd_;
};

}  // namespace mipnerf::ops
