// CPU reference of kernels/activations.cl.
#include "ref/activations.hpp"

#include <algorithm>
#include <cmath>

namespace mipnerf::ref {
namespace {

double sigmoid(double x) {
  const double e = std::exp(-std::abs(x));
  return x >= 0 ? 1.0 / (1.0 + e) : e / (1.0 + e);
}

}  // namespace

double density_activation(const ActivationOptions& options, double raw) {
  const double x = raw + options.density_bias;
  if (options.density == DensityActivation::relu) return std::max(x, 0.0);
  return std::max(x, 0.0) + std::log1p(std::exp(-std::abs(x)));  // softplus without overflow
}

double density_activation_grad(const ActivationOptions& options, double raw) {
  const double x = raw + options.density_bias;
  if (options.density == DensityActivation::relu) return x > 0 ? 1.0 : 0.0;
  return sigmoid(x);
}

double rgb_activation(const ActivationOptions& options, double raw) {
  return (1.0 + 2.0 * options.rgb_padding) * sigmoid(raw) - options.rgb_padding;
}

double rgb_activation_grad(const ActivationOptions& options, double raw) {
  const double e = std::exp(-std::abs(raw));
  return (1.0 + 2.0 * options.rgb_padding) * e / ((1.0 + e) * (1.0 + e));
}

void activations_fwd(const ActivationOptions& options, const std::vector<double>& raw_density,
                     const std::vector<double>& raw_rgb, std::vector<double>& density, std::vector<double>& rgb,
                     size_t n_rows) {
  density.resize(n_rows);
  rgb.resize(3 * n_rows);
  for (size_t i = 0; i < n_rows; ++i) {
    density[i] = density_activation(options, raw_density[i]);
    for (size_t c = 0; c < 3; ++c) rgb[3 * i + c] = rgb_activation(options, raw_rgb[3 * i + c]);
  }
}

void activations_bwd(const ActivationOptions& options, const std::vector<double>& raw_density,
                     const std::vector<double>& raw_rgb, const std::vector<double>& d_density,
                     const std::vector<double>& d_rgb, std::vector<double>& d_raw_density,
                     std::vector<double>& d_raw_rgb, size_t n_rows) {
  d_raw_density.resize(n_rows);
  d_raw_rgb.resize(3 * n_rows);
  for (size_t i = 0; i < n_rows; ++i) {
    d_raw_density[i] = d_density[i] * density_activation_grad(options, raw_density[i]);
    for (size_t c = 0; c < 3; ++c) {
      d_raw_rgb[3 * i + c] = d_rgb[3 * i + c] * rgb_activation_grad(options, raw_rgb[3 * i + c]);
    }
  }
}

}  // namespace mipnerf::ref
