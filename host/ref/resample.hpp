// CPU reference of kernels/resample.cl in double precision: hierarchical resampling of interval edges.
#pragma once

#include <cstddef>
#include <vector>

#include "core/stage_options.hpp"

namespace mipnerf::ref {

// Steps 1–4 of resample_fwd for one ray's weights w [N]: cdf [N+1] with cdf[0] = 0 and cdf[N] = 1 (official
// blur-pool, padding, 1e-5 floor on the sum, min(1, cumsum) between).
std::vector<double> resample_cdf(const ResampleOptions& options, const double* weights, size_t n_samples);

// Mirror of resample_fwd (mip-NeRF §3.2's blurred, α-padded weights; official resample_along_rays +
// sorted_piecewise_constant_pdf):
// blur-pool the weights [R][N] (max of neighbours, then mean of pairs), add the padding α, normalise (with the
// official 1e-5 floor on the sum), and invert the piecewise-constant CDF over the edges t_edges [R][N+1] at
// M + 1 sorted u (linspace(0, 1 − ε) or stratified with RNG_STREAM_RESAMPLE) → t_new [R][M+1], M = n_new
// (official num_samples = M + 1; mip-NeRF uses M = N).
// Written as the official code: the whole CDF, then a search per u (not the kernel's merge walk).
void resample_fwd(const ResampleOptions& options, const std::vector<double>& t_edges,
                  const std::vector<double>& weights, std::vector<double>& t_new, size_t n_rays, size_t n_samples,
                  size_t n_new, const RngKey& key);

}  // namespace mipnerf::ref
