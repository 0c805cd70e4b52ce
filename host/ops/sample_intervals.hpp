// Host wrapper of kernels/sample_intervals.cl: proposal sampling's sampler (official stepfun.sample_intervals with
// the annealed, padded resampling logits of models.py). Not yet a stage of the training graph (issues 45 and 46).
#pragma once

#include <cstddef>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "core/stage_options.hpp"

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
  explicit SampleIntervals(ocl::Context& ctx);

  // Enqueues sample_intervals_fwd: s_new [R][M+1], sorted, inside [domain_near, domain_far], a constant for the
  // gradient. The key draws the jitter (RNG_STREAM_PROPOSAL) when options.randomized.
  void fwd(const SampleIntervalsOptions& options, const SampleIntervalsInputs& in, ocl::DeviceArray<float>& s_new,
           const RngKey& key = {});

 private:
  ocl::Context* ctx_;
  ::cl::Kernel* fwd_;
};

}  // namespace mipnerf::ops
