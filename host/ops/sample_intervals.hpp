// Host wrapper of kernels/sample_intervals.cl: proposal sampling's sampler (official stepfun.sample_intervals with
// the annealed, padded resampling logits of models.py), and the s → t of its ray distance (linear for bounded scenes,
// the power ladder for unbounded ones). The training graph's
// proposal sampling (graph.hpp, Sampling::proposal) runs both.
#pragma once

#include <cstddef>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "core/stage_options.hpp"
#include "ops/ray_bundle.hpp"

namespace mipnerf::ops {

struct SampleIntervalsInputs {
  const ocl::DeviceArray<float>& s_edges;  // [R][N+1] the previous level's edges, sorted, normalised s-space
  const ocl::DeviceArray<float>& weights;  // [R][N] its weights (w ≥ 0)
  size_t n_rays;
  size_t n_intervals;    // N ≥ 1
  size_t new_intervals;  // M ≥ 2: intervals to draw, s_new [R][M+1] (the official's num_samples)
};

class SampleIntervals {
 public:
  // `ray_distance` compiles s_to_t's warp in (RAY_DISTANCE).
  explicit SampleIntervals(ocl::Context& ctx, RayDistance ray_distance = RayDistance::linear);
  RayDistance ray_distance() const { return ray_distance_; }

  // Enqueues sample_intervals_fwd: s_new [R][M+1], sorted, inside [domain_near, domain_far], a constant for the
  // gradient. The key draws the jitter (RNG_STREAM_PROPOSAL) when options.randomized.
  void fwd(const SampleIntervalsOptions& options, const SampleIntervalsInputs& in, ocl::DeviceArray<float>& s_new,
           const RngKey& key = {});

  // Enqueues sample_intervals_s_to_t: t [R][K] from s [R][K] by the ray distance, with each ray's near and far from
  // `rays`: linear clip(s·far + (1 − s)·near, near, far) (the official identity ray warp, bounded scenes) or the
  // power ladder (kernels/sample_intervals.cl, unbounded scenes). K = n_per_ray ≥ 1.
  void s_to_t(const ocl::DeviceArray<float>& s, const RayBundle& rays, size_t n_rays, size_t n_per_ray,
              ocl::DeviceArray<float>& t);

 private:
  ocl::Context* ctx_;
  RayDistance ray_distance_;
  ::cl::Kernel* fwd_;
  ::cl::Kernel* s_to_t_;
};

}  // namespace mipnerf::ops
