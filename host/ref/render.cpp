// CPU reference of kernels/render.cl.
#include "ref/render.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/rng.hpp"
#include "ref/activations.hpp"

namespace mipnerf::ref {
namespace {

double norm3(const double* v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

// The raw densities as the activation sees them: raw + σ·z with σ = options.density_noise (raw itself for σ = 0).
std::vector<double> noisy_raw_density(const RenderOptions& options, const std::vector<double>& raw_density,
                                      size_t n_rays, size_t n_samples, const DensityNoiseKey& noise) {
  std::vector<double> out(raw_density.begin(), raw_density.begin() + n_rays * n_samples);
  if (options.density_noise > 0) {
    const auto z = density_noise_draws(noise, n_rays, n_samples);
    for (size_t k = 0; k < out.size(); ++k) out[k] += static_cast<double>(options.density_noise) * z[k];
  }
  return out;
}

// s_i = σ_i·δ_i, 0 for an empty interval (as the kernel: σ = ∞ with δ = 0 is no NaN); ∞ for the last of
// n_samples with an opaque background (OPAQUE_BACKGROUND), whatever its density and length.
double thickness(double density, double t0, double t1, double dir_norm, bool opaque_last = false) {
  if (opaque_last) return std::numeric_limits<double>::infinity();
  const double delta = (t1 - t0) * dir_norm;
  return delta > 0 ? density * delta : 0.0;
}

// One ray's ∂L/∂σ from the gradients g [N] = ∂L/∂w on its weights w [N] (the forward's), densities σ [N] and edges
// t [N+1]: ∂L/∂σ_i = δ_i·(g_i·T_{i+1} − Σ_{k>i} g_k·w_k), since ∂w_i/∂s_i = e^{−s_i}·T_i = T_{i+1} and
// ∂w_k/∂s_i = −w_k for k > i (w_k = α_k·T_k, T_k = exp(−Σ_{j<k} s_j)); T_{i+1} = exp(−Σ_{j≤i} s_j) directly, the
// suffix sum from the back; 0 on an empty interval (δ = 0: s_i does not depend on σ_i). With `opaque` the last
// interval's s is ∞ (T_N = 0), so its own ∂L/∂σ is 0. Writes d_density [N].
void density_grad_of_ray(const double* g, const double* weights, const double* density, const double* t,
                         double dir_norm, size_t n_samples, bool opaque, double* d_density) {
  std::vector<double> trans_next(n_samples), delta(n_samples);
  double optical_depth = 0.0;
  for (size_t i = 0; i < n_samples; ++i) {
    delta[i] = (t[i + 1] - t[i]) * dir_norm;
    optical_depth += thickness(density[i], t[i], t[i + 1], dir_norm, opaque && i + 1 == n_samples);
    trans_next[i] = std::exp(-optical_depth);  // T_{i+1}
  }
  double suffix = 0.0;  // Σ_{k>i} g_k·w_k
  for (size_t r = 0; r < n_samples; ++r) {
    const size_t i = n_samples - 1 - r;
    d_density[i] = delta[i] > 0 ? delta[i] * (g[i] * trans_next[i] - suffix) : 0.0;
    suffix += g[i] * weights[i];
  }
}

// d_density [R][N] = ∂L/∂σ from d_weights [R][N] = ∂L/∂w on activated densities: render_raw_weights_bwd before the
// activation (density_grad_of_ray per ray, with g = d_weights).
void render_weights_bwd(bool opaque, const std::vector<double>& density, const std::vector<double>& t_edges,
                        const std::vector<double>& directions, const std::vector<double>& weights,
                        const std::vector<double>& d_weights, std::vector<double>& d_density, size_t n_rays,
                        size_t n_samples) {
  d_density.assign(n_rays * n_samples, 0.0);
  for (size_t ray = 0; ray < n_rays; ++ray) {
    const size_t first = ray * n_samples;
    density_grad_of_ray(d_weights.data() + first, weights.data() + first, density.data() + first,
                        t_edges.data() + ray * (n_samples + 1), norm3(directions.data() + 3 * ray), n_samples, opaque,
                        d_density.data() + first);
  }
}

}  // namespace

std::vector<double> density_noise_draws(const DensityNoiseKey& noise, size_t n_rays, size_t n_samples) {
  constexpr uint32_t level_shift = 24;  // DENSITY_NOISE_LEVEL_SHIFT
  std::vector<double> z(n_rays * n_samples);
  for (size_t ray = 0; ray < n_rays; ++ray) {
    for (size_t group = 0; 4 * group < n_samples; ++group) {
      const auto draws =
          rng_normal4(noise.rng.seed, noise.rng.first_ray + static_cast<uint32_t>(ray), noise.rng.step,
                      (noise.level << level_shift) + static_cast<uint32_t>(group), rng_stream_density_noise);
      for (size_t k = 0; k < 4 && 4 * group + k < n_samples; ++k) z[ray * n_samples + 4 * group + k] = draws[k];
    }
  }
  return z;
}

void render_fwd(const RenderOptions& options, const std::vector<double>& rgb, const std::vector<double>& density,
                const std::vector<double>& t_edges, const std::vector<double>& directions,
                std::vector<double>& comp_rgb, std::vector<double>& acc, std::vector<double>& distance,
                std::vector<double>& weights, size_t n_rays, size_t n_samples) {
  comp_rgb.assign(3 * n_rays, 0.0);
  acc.assign(n_rays, 0.0);
  distance.assign(n_rays, 0.0);
  weights.assign(n_rays * n_samples, 0.0);
  for (size_t ray = 0; ray < n_rays; ++ray) {
    const double* t = t_edges.data() + ray * (n_samples + 1);
    const double dir_norm = norm3(directions.data() + 3 * ray);
    double optical_depth = 0.0, t_weighted = 0.0, sum = 0.0;
    for (size_t i = 0; i < n_samples; ++i) {
      const size_t at = ray * n_samples + i;
      const bool opaque_last = options.opaque_background && i + 1 == n_samples;
      const double s = thickness(density[at], t[i], t[i + 1], dir_norm, opaque_last);
      const double w = -std::expm1(-s) * std::exp(-optical_depth);
      weights[at] = w;
      for (int c = 0; c < 3; ++c) comp_rgb[3 * ray + c] += w * rgb[3 * at + c];
      sum += w;
      t_weighted += w * 0.5 * (t[i] + t[i + 1]);
      optical_depth += s;
    }
    acc[ray] = sum;
    distance[ray] = std::clamp(sum > 0 ? t_weighted / sum : t[0], t[0], t[n_samples]);
    if (options.background == Background::white) {
      for (int c = 0; c < 3; ++c) comp_rgb[3 * ray + c] += 1.0 - sum;
    }
  }
}

void render_bwd(const RenderOptions& options, const std::vector<double>& rgb, const std::vector<double>& density,
                const std::vector<double>& t_edges, const std::vector<double>& directions,
                const std::vector<double>& weights, const std::vector<double>& d_comp_rgb,
                const std::vector<double>* d_acc, std::vector<double>& d_rgb, std::vector<double>& d_density,
                size_t n_rays, size_t n_samples, const std::vector<double>* d_weights) {
  d_rgb.assign(3 * n_rays * n_samples, 0.0);
  d_density.assign(n_rays * n_samples, 0.0);
  std::vector<double> g(n_samples);
  for (size_t ray = 0; ray < n_rays; ++ray) {
    const double* d_comp = d_comp_rgb.data() + 3 * ray;
    double d_acc_total = d_acc ? (*d_acc)[ray] : 0.0;
    if (options.background == Background::white) d_acc_total -= d_comp[0] + d_comp[1] + d_comp[2];
    for (size_t i = 0; i < n_samples; ++i) {
      const size_t at = ray * n_samples + i;
      g[i] = d_acc_total + (d_weights ? (*d_weights)[at] : 0.0);
      for (int c = 0; c < 3; ++c) {
        g[i] += d_comp[c] * rgb[3 * at + c];
        d_rgb[3 * at + c] = d_comp[c] * weights[at];
      }
    }
    density_grad_of_ray(g.data(), weights.data() + ray * n_samples, density.data() + ray * n_samples,
                        t_edges.data() + ray * (n_samples + 1), norm3(directions.data() + 3 * ray), n_samples,
                        options.opaque_background, d_density.data() + ray * n_samples);
  }
}

void render_raw_fwd(const RenderOptions& options, const ActivationOptions& activation,
                    const std::vector<double>& raw_rgb, const std::vector<double>& raw_density,
                    const std::vector<double>& t_edges, const std::vector<double>& directions,
                    std::vector<double>& comp_rgb, std::vector<double>& acc, std::vector<double>& distance,
                    std::vector<double>& weights, size_t n_rays, size_t n_samples, const DensityNoiseKey& noise) {
  std::vector<double> density, rgb;
  activations_fwd(activation, noisy_raw_density(options, raw_density, n_rays, n_samples, noise), raw_rgb, density, rgb,
                  n_rays * n_samples);
  render_fwd(options, rgb, density, t_edges, directions, comp_rgb, acc, distance, weights, n_rays, n_samples);
}

void render_raw_weights_fwd(const RenderOptions& options, const ActivationOptions& activation,
                            const std::vector<double>& raw_density, const std::vector<double>& t_edges,
                            const std::vector<double>& directions, std::vector<double>& acc,
                            std::vector<double>& distance, std::vector<double>& weights, size_t n_rays,
                            size_t n_samples, const DensityNoiseKey& noise) {
  const std::vector<double> no_colour(3 * n_rays * n_samples, 0.0);
  std::vector<double> unused_comp_rgb;
  render_raw_fwd(options, activation, no_colour, raw_density, t_edges, directions, unused_comp_rgb, acc, distance,
                 weights, n_rays, n_samples, noise);
}

void render_raw_bwd(const RenderOptions& options, const ActivationOptions& activation,
                    const std::vector<double>& raw_rgb, const std::vector<double>& raw_density,
                    const std::vector<double>& t_edges, const std::vector<double>& directions,
                    const std::vector<double>& weights, const std::vector<double>& d_comp_rgb,
                    const std::vector<double>* d_acc, std::vector<double>& d_raw_rgb,
                    std::vector<double>& d_raw_density, size_t n_rays, size_t n_samples, const DensityNoiseKey& noise,
                    const std::vector<double>* d_weights) {
  const size_t rows = n_rays * n_samples;
  const auto noisy = noisy_raw_density(options, raw_density, n_rays, n_samples, noise);
  std::vector<double> density, rgb, d_rgb, d_density;
  activations_fwd(activation, noisy, raw_rgb, density, rgb, rows);
  render_bwd(options, rgb, density, t_edges, directions, weights, d_comp_rgb, d_acc, d_rgb, d_density, n_rays,
             n_samples, d_weights);
  activations_bwd(activation, noisy, raw_rgb, d_density, d_rgb, d_raw_density, d_raw_rgb, rows);
}

void render_raw_weights_bwd(const RenderOptions& options, const ActivationOptions& activation,
                            const std::vector<double>& raw_density, const std::vector<double>& t_edges,
                            const std::vector<double>& directions, const std::vector<double>& weights,
                            const std::vector<double>& d_weights, std::vector<double>& d_raw_density, size_t n_rays,
                            size_t n_samples, const DensityNoiseKey& noise) {
  const size_t rows = n_rays * n_samples;
  const auto noisy = noisy_raw_density(options, raw_density, n_rays, n_samples, noise);
  const std::vector<double> no_colour(3 * rows, 0.0);  // activations_* take colours too; none enters the weights
  std::vector<double> density, unused_rgb, d_density, unused_d_raw_rgb;
  activations_fwd(activation, noisy, no_colour, density, unused_rgb, rows);
  render_weights_bwd(options.opaque_background, density, t_edges, directions, weights, d_weights, d_density, n_rays,
                     n_samples);
  activations_bwd(activation, noisy, no_colour, d_density, no_colour, d_raw_density, unused_d_raw_rgb, rows);
}

}  // namespace mipnerf::ref
