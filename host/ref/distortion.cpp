// CPU reference (double) of kernels/distortion.cl.
#include "ref/distortion.hpp"

#include <cmath>

namespace mipnerf::ref {

void distortion_fwd(const double* t, const double* w, double* ray_loss, size_t n_rays, size_t n_intervals) {
  for (size_t ray = 0; ray < n_rays; ++ray) {
    const double* rt = t + ray * (n_intervals + 1);
    const double* rw = w + ray * n_intervals;
    double weight_below = 0.0, spread_below = 0.0, loss = 0.0;  // W_{<i}, A_i
    for (size_t i = 0; i < n_intervals; ++i) {
      if (i > 0) spread_below += weight_below * 0.5 * (rt[i + 1] - rt[i - 1]);
      loss += rw[i] * (2.0 * spread_below + rw[i] * (rt[i + 1] - rt[i]) / 3.0);
      weight_below += rw[i];
    }
    ray_loss[ray] = loss;
  }
}

void distortion_bwd(const double* t, const double* w, double grad_scale, double* d_w, double* d_t, size_t n_rays,
                    size_t n_intervals) {
  for (size_t ray = 0; ray < n_rays; ++ray) {
    const double* rt = t + ray * (n_intervals + 1);
    const double* rw = w + ray * n_intervals;
    double* rdw = d_w + ray * n_intervals;
    double* rdt = d_t + ray * (n_intervals + 1);
    double weight_above = 0.0, spread_above = 0.0;  // W_{>k}, B_k
    for (size_t k = n_intervals; k-- > 0;) {
      if (k + 1 < n_intervals) spread_above += weight_above * 0.5 * (rt[k + 2] - rt[k]);
      rdw[k] = spread_above;
      weight_above += rw[k];
    }
    const double weight_total = weight_above;
    double weight_below = 0.0, spread_below = 0.0, d_t_from_left = 0.0;
    for (size_t k = 0; k < n_intervals; ++k) {
      if (k > 0) spread_below += weight_below * 0.5 * (rt[k + 1] - rt[k - 1]);
      const double wk = rw[k], width = rt[k + 1] - rt[k];
      rdw[k] = grad_scale * (2.0 * (spread_below + rdw[k]) + 2.0 / 3.0 * wk * width);
      const double d_u = 2.0 * wk * (weight_below - (weight_total - weight_below - wk));
      const double self = wk * wk / 3.0;
      rdt[k] = grad_scale * (d_t_from_left + 0.5 * d_u - self);
      d_t_from_left = 0.5 * d_u + self;
      weight_below += wk;
    }
    rdt[n_intervals] = grad_scale * d_t_from_left;
  }
}

double distortion_quadratic(const double* t, const double* w, size_t n_intervals) {
  double inter = 0.0, intra = 0.0;
  for (size_t i = 0; i < n_intervals; ++i) {
    const double ui = 0.5 * (t[i] + t[i + 1]);
    for (size_t j = 0; j < n_intervals; ++j) inter += w[i] * w[j] * std::abs(ui - 0.5 * (t[j] + t[j + 1]));
    intra += w[i] * w[i] * (t[i + 1] - t[i]);
  }
  return inter + intra / 3.0;
}

double distortion_loss(const std::vector<double>& ray_loss, double mult) {
  double sum = 0.0;
  for (double v : ray_loss) sum += v;
  return mult * sum / static_cast<double>(ray_loss.size());
}

}  // namespace mipnerf::ref
