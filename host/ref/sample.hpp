// CPU reference of kernels/sample.cl in double precision: stratified edges and the sorted union of two edge sets.
#pragma once

#include <cstddef>
#include <vector>

#include "core/stage_options.hpp"

namespace mipnerf::ref {

// Mirror of sample_stratified_fwd (NeRF eq. 2's stratified sampling, official sample_along_rays): t_edges [R][N+1]
// between near [R] and far [R], linear in depth or disparity, deterministic or jittered within the midpoints of
// neighbouring edges, with the kernel's uniforms (rng_uniform4, RNG_STREAM_STRATIFIED, keyed by (seed, step,
// first_ray + ray)).
void sample_stratified_fwd(const SampleOptions& options, const std::vector<double>& near,
                           const std::vector<double>& far, std::vector<double>& t_edges, size_t n_rays,
                           size_t n_samples, const RngKey& key);

// Mirror of sample_merge_fwd: t_out [R][len_a + len_b], the sorted union of t_a [R][len_a] and t_b [R][len_b].
void sample_merge_fwd(const std::vector<double>& t_a, const std::vector<double>& t_b, std::vector<double>& t_out,
                      size_t n_rays, size_t len_a, size_t len_b);

}  // namespace mipnerf::ref
