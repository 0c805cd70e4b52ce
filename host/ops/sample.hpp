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

// sample_stratified_fwd's items (SAMPLE_GROUPS_PER_VECTOR of sample.cl): one per group of 4 edges, or one per 16
// consecutive groups of a ray as uint16/float16, which PoCL's CPU device runs in full-width vector registers
// (bench/results/kernel_runtimes/kernel_runtimes_xeon.md). The same edges either way, bit for bit.
enum class SampleItems { device_default, per_group, per_vector };

// Stratified sampling and merging for one specialisation (lindisp or not; built on construction).
class Sample {
 public:
  // device_default: per vector on PoCL's CPU device, per group elsewhere.
  Sample(ocl::Context& ctx, const SampleOptions& options, SampleItems items = SampleItems::device_default);
  const SampleOptions& options() const { return options_; }
  SampleItems items() const { return items_; }

  // Enqueues sample_stratified_fwd: t_edges [R][N+1] (options().randomized chooses jitter; `key` keys it).
  void stratified(const StratifiedInputs& in, ocl::DeviceArray<float>& t_edges, const RngKey& key = {});
  // Enqueues sample_merge_fwd: t_out [R][len_a + len_b], the sorted union per ray (NeRF's coarse ∪ fine).
  void merge(const MergeInputs& in, ocl::DeviceArray<float>& t_out);

 private:
  ocl::Context* ctx_;
  SampleOptions options_;
  SampleItems items_;  // never device_default
  ::cl::Kernel* stratified_;
  ::cl::Kernel* merge_;
};

}  // namespace mipnerf::ops
