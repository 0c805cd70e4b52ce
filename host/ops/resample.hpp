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
// resample_fwd's items (RESAMPLE_RAYS_PER_VECTOR of resample.cl): one per ray, or one per 16 rays walked together
// lane by lane, which PoCL's CPU device runs without a mispredicted branch per step of a ray's walk
// (bench/results/kernel_runtimes/kernel_runtimes_xeon.md). The same edges either way, bit for bit.
enum class ResampleItems { device_default, per_ray, per_vector };

class Resample {
 public:
  // device_default: per vector on PoCL's CPU device, per ray elsewhere.
  explicit Resample(ocl::Context& ctx, ResampleItems items = ResampleItems::device_default);
  ResampleItems items() const { return items_; }

  // Enqueues resample_fwd: t_new [R][M+1], sorted, a constant for the gradient.
  void fwd(const ResampleOptions& options, const ResampleInputs& in, ocl::DeviceArray<float>& t_new,
           const RngKey& key = {});

 private:
  ocl::Context* ctx_;
  ResampleItems items_;  // never device_default
  ::cl::Kernel* fwd_;
};

}  // namespace mipnerf::ops
