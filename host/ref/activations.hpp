// CPU reference of kernels/activations.cl in double precision.
#pragma once

#include <cstddef>
#include <vector>

#include "core/stage_options.hpp"

namespace mipnerf::ref {

// The activations of one value and their derivatives (mip-NeRF §4/official models.py: density =
// softplus(raw + bias), rgb = (1 + 2ε)·sigmoid(raw) − ε; NeRF: relu, plain sigmoid).
double density_activation(const ActivationOptions& options, double raw);
double density_activation_grad(const ActivationOptions& options, double raw);
double rgb_activation(const ActivationOptions& options, double raw);
double rgb_activation_grad(const ActivationOptions& options, double raw);

// Mirror of activations_fwd: density [rows], rgb [rows][3] from raw_density [rows], raw_rgb [rows][3].
void activations_fwd(const ActivationOptions& options, const std::vector<double>& raw_density,
                     const std::vector<double>& raw_rgb, std::vector<double>& density, std::vector<double>& rgb,
                     size_t n_rows);

// Mirror of activations_bwd: d_raw_density [rows], d_raw_rgb [rows][3] (chain rule through the activations).
void activations_bwd(const ActivationOptions& options, const std::vector<double>& raw_density,
                     const std::vector<double>& raw_rgb, const std::vector<double>& d_density,
                     const std::vector<double>& d_rgb, std::vector<double>& d_raw_density,
                     std::vector<double>& d_raw_rgb, size_t n_rows);

}  // namespace mipnerf::ref
