// CPU reference of the MLP in double precision: mirrors of kernels/mlp.cl (same names, argument order and
// layouts), and the whole network's forward and backward written the plain way — concatenations copied,
// the view encoding tiled to every sample — as an independent oracle for the device's split products.
#pragma once

#include <cstddef>
#include <vector>

#include "mlp/mlp_config.hpp"

namespace mipnerf::ref {

// ---- Mirrors of kernels/mlp.cl (views: element (r, c) at base[offset + r·ld + c]) ----

// z[r][c] = act(z[r][c] + params[bias_offset + c]); act = ReLU (NaN kept) when apply_relu.
void mlp_bias_act_fwd(double* z, size_t z_offset, size_t ld, size_t rows, size_t cols, const double* params,
                      size_t bias_offset, bool apply_relu);

// z[r][c] = ReLU(z[r][c] + ray_term[r / samples_per_ray][c] + params[bias_offset + c]).
void mlp_bias_ray_relu_fwd(double* z, size_t z_offset, size_t ld, size_t rows, size_t cols, const double* params,
                           size_t bias_offset, const double* ray_term, size_t samples_per_ray);

// apply_relu: dz masked by act > 0 in place; partials[b][c] = Σ dz over the rows of block b.
void mlp_act_bwd_partial(double* dz, size_t dz_offset, size_t dz_ld, const double* act, size_t act_offset,
                         size_t act_ld, size_t rows, size_t cols, size_t rows_per_block, bool apply_relu,
                         double* partials);

// grad[grad_offset + c] += Σ_b partials[b][c].
void mlp_sum_partials(const double* partials, size_t n_blocks, size_t cols, double* grad, size_t grad_offset);

// ---- The whole network (mirrors mlp::Network::forward / backward) ----

// What the reference forward keeps for its backward.
struct MlpTape {
  size_t n_rays = 0;
  size_t samples_per_ray = 0;
  std::vector<std::vector<double>> trunk_inputs;  // per trunk layer: its input [rows][in], concatenation copied
  std::vector<std::vector<double>> activations;   // per trunk layer: ReLU output [rows][width]
  std::vector<double> bottleneck;                 // [rows][bottleneck_width]
  std::vector<double> view_input;                 // [rows][bottleneck_width + view_width], encoding tiled
  std::vector<double> view_hidden;                // [rows][view_branch_width]
};

// features [rows][input_width], view_encoding [n_rays][view_width] (ignored without view dependence),
// params in mlp::parameter_layout(config) order → raw_density [rows][density_outputs], raw_rgb [rows][rgb_outputs].
void mlp_forward(const mlp::MlpConfig& config, const std::vector<double>& params, const std::vector<double>& features,
                 const std::vector<double>& view_encoding, size_t n_rays, size_t samples_per_ray,
                 std::vector<double>& raw_density, std::vector<double>& raw_rgb, MlpTape* tape = nullptr);

// grads (parameter layout, resized if empty) += ∂loss/∂params for ∂loss/∂raw_density and ∂loss/∂raw_rgb.
// d_features (optional): set to ∂loss/∂features [rows][input_width] (resized, overwritten), the first trunk layer's
// input gradient plus every skip layer's through the features' columns of its concatenated input.
void mlp_backward(const mlp::MlpConfig& config, const std::vector<double>& params, const MlpTape& tape,
                  const std::vector<double>& d_raw_density, const std::vector<double>& d_raw_rgb,
                  std::vector<double>& grads, std::vector<double>* d_features = nullptr);

}  // namespace mipnerf::ref
