// Host wrapper of kernels/resample.cl: hierarchical resampling from the weights of a previous level.
#pragma once

#include <cstddef>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "core/stage_options.hpp"

namespace mipnerf::ops {

struct ResampleInputs {
  const ocl::DeviceArray<float>& t_edges;  // [R][N+1] the previous level's edges
  const ocl::DeviceArray<float>& weights;  // [R][N] its rendering weights
  size_t n_rays;
  size_t n_samples;    // N: the previous level's intervals
  size_t new_samples;  // M ≥ 1: intervals to draw, t_new [R][M+1] (mip-NeRF: M = N; NeRF: its own count)
};

// Hierarchical resampling (no compile-time options; the ResampleOptions are kernel arguments).
class Resample {
 public:
  explicit Resample(ocl::Context& ctx);

  // Enqueues resample_fwd: t_new [R][M+1], sorted, a constant for the gradient.
  void fwd(const ResampleOptions& options, const ResampleInputs& in, ocl::DeviceArray<float>& t_new,
           const RngKey& key = {});

 private:
  ocl::Context* ctx_;
  ::cl::Kernel* fwd_;
};

}  // namespace mipnerf::ops
