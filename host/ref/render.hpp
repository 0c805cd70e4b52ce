// CPU reference of kernels/render.cl in double precision: volume rendering and its backward.
#pragma once

#include <cstddef>
#include <vector>

#include "core/stage_options.hpp"

namespace mipnerf::ref {

// Mirror of render_fwd (NeRF eq. 3 as in official volumetric_rendering): δ_i = (t_{i+1} − t_i)·|d|,
// α_i = 1 − exp(−σ_i·δ_i), T_i = exp(−Σ_{j<i} σ_j·δ_j), w_i = α_i·T_i; comp_rgb [R][3] = Σ w_i·c_i (+ 1 − acc on
// white), acc [R] = Σ w_i, distance [R] = Σ w_i·t_mid_i / acc clipped to [t_0, t_N] (t_0 when acc = 0),
// weights [R][N]. Inputs rgb [R][N][3], density [R][N], t_edges [R][N+1], directions [R][3].
void render_fwd(const RenderOptions& options, const std::vector<double>& rgb, const std::vector<double>& density,
                const std::vector<double>& t_edges, const std::vector<double>& directions,
                std::vector<double>& comp_rgb, std::vector<double>& acc, std::vector<double>& distance,
                std::vector<double>& weights, size_t n_rays, size_t n_samples);

// Mirror of render_bwd: d_rgb [R][N][3], d_density [R][N] from d_comp_rgb [R][3] and, when d_acc is not null,
// d_acc [R], and when d_weights is not null, d_weights [R][N] (∂L/∂w of a loss on the weights, added to g). Computed directly from the chain rule, ∂L/∂σ_i = δ_i·(g_i·T_{i+1} − Σ_{k>i} g_k·w_k) with
// g_i = ∂L/∂w_i, T_{i+1} = exp(−Σ_{j≤i} s_j); `weights` are the forward's.
void render_bwd(const RenderOptions& options, const std::vector<double>& rgb, const std::vector<double>& density,
                const std::vector<double>& t_edges, const std::vector<double>& directions,
                const std::vector<double>& weights, const std::vector<double>& d_comp_rgb,
                const std::vector<double>* d_acc, std::vector<double>& d_rgb, std::vector<double>& d_density,
                size_t n_rays, size_t n_samples, const std::vector<double>* d_weights = nullptr);

// The N(0, 1) draws of the density noise, z [R][N]: sample i of ray r takes draw i % 4 of rng_normal4(seed,
// first_ray + r, step, level·2^24 + i/4, RNG_STREAM_DENSITY_NOISE) (kernels/render.cl), in double.
std::vector<double> density_noise_draws(const DensityNoiseKey& noise, size_t n_rays, size_t n_samples);

// Mirrors of the fused kernels: ref::activations_fwd then ref::render_fwd, and render_bwd then activations_bwd.
// With options.density_noise = σ > 0, the activations read raw_density + σ·z (z: density_noise_draws of `noise`;
// official models.py adds density_noise·N(0, 1) to the raw density before its activation while training), and the
// backward differentiates at that noisy value (∂(raw + σ·z)/∂raw = 1).
void render_raw_fwd(const RenderOptions& options, const ActivationOptions& activation,
                    const std::vector<double>& raw_rgb, const std::vector<double>& raw_density,
                    const std::vector<double>& t_edges, const std::vector<double>& directions,
                    std::vector<double>& comp_rgb, std::vector<double>& acc, std::vector<double>& distance,
                    std::vector<double>& weights, size_t n_rays, size_t n_samples, const DensityNoiseKey& noise = {});
// Mirror of render_raw_weights_fwd: render_raw_fwd's acc, distance and weights from the raw densities alone (no
// colour is read or composited; in this reference the colours never touch those three, so it runs render_raw_fwd on
// zero colours and drops the composite).
void render_raw_weights_fwd(const RenderOptions& options, const ActivationOptions& activation,
                            const std::vector<double>& raw_density, const std::vector<double>& t_edges,
                            const std::vector<double>& directions, std::vector<double>& acc,
                            std::vector<double>& distance, std::vector<double>& weights, size_t n_rays,
                            size_t n_samples, const DensityNoiseKey& noise = {});
// Mirror of render_raw_weights_bwd: d_raw_density [R][N] from d_weights [R][N] = ∂L/∂w, as render_bwd's
// ∂L/∂σ_i = δ_i·(g_i·T_{i+1} − Σ_{k>i} g_k·w_k) with g = d_weights, then through the density activation, at the
// noisy raw value when options.density_noise > 0 (keyed by `noise`, the forward's). `weights` are
// render_raw_weights_fwd's; the background does not enter.
void render_raw_weights_bwd(const RenderOptions& options, const ActivationOptions& activation,
                            const std::vector<double>& raw_density, const std::vector<double>& t_edges,
                            const std::vector<double>& directions, const std::vector<double>& weights,
                            const std::vector<double>& d_weights, std::vector<double>& d_raw_density, size_t n_rays,
                            size_t n_samples, const DensityNoiseKey& noise = {});
void render_raw_bwd(const RenderOptions& options, const ActivationOptions& activation,
                    const std::vector<double>& raw_rgb, const std::vector<double>& raw_density,
                    const std::vector<double>& t_edges, const std::vector<double>& directions,
                    const std::vector<double>& weights, const std::vector<double>& d_comp_rgb,
                    const std::vector<double>* d_acc, std::vector<double>& d_raw_rgb,
                    std::vector<double>& d_raw_density, size_t n_rays, size_t n_samples,
                    const DensityNoiseKey& noise = {}, const std::vector<double>* d_weights = nullptr);

}  // namespace mipnerf::ref
