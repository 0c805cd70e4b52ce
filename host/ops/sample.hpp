// Host wrapper of kernels/sample.cl: stratified interval edges, and the sorted union of two edge sets.
#pragma once

#include <cstddef>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "cl/program.hpp"
#include "core/stage_options.hpp"
#include "ops/ray_bundle.hpp"

namespace mipnerf::ops {

ocl::BuildOptions sample_build_options(const SampleOptions& options);  // SAMPLE_LINDISP

struct StratifiedInputs {
  const RayBundle& rays;  // reads near and far
  size_t n_rays;          // R ≤ rays.n_rays(): the bundle's first R rays
  size_t n_samples;       // N intervals → N + 1 edges per ray
};

struct MergeInputs {
  const ocl::DeviceArray<float>& t_a;  // [R][len_a] sorted per ray
  const ocl::DeviceArray<float>& t_b;  // [R][len_b] sorted per ray
  size_t n_rays;
  size_t len_a;
  size_t len_b;
};

// Stratified sampling and merging for one specialisation (lindisp or not; built on construction).
class Sample {
 public:
  Sample(ocl::Context& ctx, const SampleOptions& options);
  const SampleOptions& options() const { return options_; }

  // Enqueues sample_stratified_fwd: t_edges [R][N+1] (options().randomized chooses jitter; `key` keys it).
  void stratified(const StratifiedInputs& in, ocl::DeviceArray<float>& t_edges, const RngKey& key = {});
  // Enqueues sample_merge_fwd: t_out [R][len_a + len_b], the sorted union per ray (NeRF's coarse ∪ fine).
  void merge(const MergeInputs& in, ocl::DeviceArray<float>& t_out);

 private:
  ocl::Context* ctx_;
  SampleOptions options_;
  ::cl::Kernel* stratified_;
  ::cl::Kernel* merge_;
};

}  // namespace mipnerf::ops
