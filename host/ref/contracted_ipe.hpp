// CPU reference (double) of kernels/contracted_ipe.cl, same names: mip-NeRF 360's encoding of a frustum, the full
// Gaussian (ref/gaussian.hpp gaussian_full_fwd) through the contraction (ref/contract.hpp), projected onto the
// directions of core/geodesic_basis.hpp and integrated-positional-encoded (official lift_and_diagonalize and
// integrated_pos_enc). Also the float32 kernel's error bound per feature, derived in contracted_ipe.cpp.
#pragma once

#include <cstddef>
#include <vector>

#include "core/stage_options.hpp"

namespace mipnerf::ref {

// The contracted Gaussians of every interval: means, covs (diagonal), cov_off [R·N][3].
void contracted_gaussians(const GaussianOptions& options, const std::vector<double>& origins,
                          const std::vector<double>& directions, const std::vector<double>& radii,
                          const std::vector<double>& t_edges, std::vector<double>& means, std::vector<double>& covs,
                          std::vector<double>& cov_off, size_t n_rays, size_t n_samples);

// Official lift_and_diagonalize: lifted_means, lifted_vars [rows][K] = (b_k·μ, b_kᵀΣb_k) for basis [K][3].
void project_gaussians(const std::vector<double>& means, const std::vector<double>& covs,
                       const std::vector<double>& cov_off, const std::vector<double>& basis,
                       std::vector<double>& lifted_means, std::vector<double>& lifted_vars, size_t n_rows);

// Official integrated_pos_enc of the lifted pairs: features [rows][2LK], sines then cosines, index l·K + k in each.
void projected_ipe(const EncodingOptions& options, const std::vector<double>& lifted_means,
                   const std::vector<double>& lifted_vars, std::vector<double>& features, size_t n_rows,
                   size_t n_basis);

// Mirror of contracted_ipe_fwd: features [R·N][2LK] from the rays, t_edges [R][N+1] and basis [K][3].
void contracted_ipe_fwd(const GaussianOptions& options, const EncodingOptions& encoding,
                        const std::vector<double>& origins, const std::vector<double>& directions,
                        const std::vector<double>& radii, const std::vector<double>& t_edges,
                        const std::vector<double>& basis, std::vector<double>& features, size_t n_rays,
                        size_t n_samples);

// The float32 kernel's error bound per feature, [R·N][2LK], for float inputs (the arguments hold float values) and a
// kernel built with a sincos every `sincos_every` degrees.
std::vector<double> contracted_ipe_fwd_float32_bound(const GaussianOptions& options, const EncodingOptions& encoding,
                                                     int sincos_every,
                                                     const std::vector<double>& origins,
                                                     const std::vector<double>& directions,
                                                     const std::vector<double>& radii,
                                                     const std::vector<double>& t_edges,
                                                     const std::vector<double>& basis, size_t n_rays,
                                                     size_t n_samples);

}  // namespace mipnerf::ref
