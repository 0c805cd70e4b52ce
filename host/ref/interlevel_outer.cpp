// CPU reference of kernels/interlevel_outer.cl (see the header).
#include "ref/interlevel_outer.hpp"

#include <algorithm>

#include "ref/interlevel.hpp"

namespace mipnerf::ref {

void outer_searchsorted(const double* a, size_t count, double v, size_t* lo, size_t* hi) {
  // The official's masks: idx_lo = max over {k : v ≥ a_k} ∪ {0}, idx_hi = min over {k : v < a_k} ∪ {count − 1}.
  *lo = 0;
  *hi = count - 1;
  for (size_t k = 0; k < count; ++k) {
    if (v >= a[k]) *lo = std::max(*lo, k);
    if (!(v >= a[k])) *hi = std::min(*hi, k);
  }
}

void outer_bounds(const double* c, size_t n_intervals, const double* cp, const double* wp, size_t n_proposal,
                  double* bound) {
  std::vector<double> cumulative(n_proposal + 1, 0.0);
  for (size_t k = 0; k < n_proposal; ++k) cumulative[k + 1] = cumulative[k] + wp[k];
  std::vector<size_t> lo(n_intervals + 1), hi(n_intervals + 1);
  for (size_t i = 0; i <= n_intervals; ++i) outer_searchsorted(cp, n_proposal + 1, c[i], &lo[i], &hi[i]);
  for (size_t j = 0; j < n_intervals; ++j) bound[j] = cumulative[hi[j + 1]] - cumulative[lo[j]];
}

double outer_interval_loss(double w, double bound) {
  const double excess = std::max(0.0, w - bound);
  return excess * excess / (w + kInterlevelEps);
}

void outer_interlevel_fwd(const double* c, const double* w, const double* cp, const double* wp, double* ray_loss,
                          size_t n_rays, size_t n_intervals, size_t n_proposal) {
  std::vector<double> bound(n_intervals);
  for (size_t ray = 0; ray < n_rays; ++ray) {
    const double* ray_w = w + ray * n_intervals;
    outer_bounds(c + ray * (n_intervals + 1), n_intervals, cp + ray * (n_proposal + 1), wp + ray * n_proposal,
                 n_proposal, bound.data());
    double sum = 0.0;
    for (size_t j = 0; j < n_intervals; ++j) sum += outer_interval_loss(ray_w[j], bound[j]);
    ray_loss[ray] = sum;
  }
}

void outer_interlevel_bwd(const double* c, const double* w, const double* cp, const double* wp, double grad_scale,
                          double* d_wp, size_t n_rays, size_t n_intervals, size_t n_proposal) {
  std::vector<double> bound(n_intervals);
  for (size_t ray = 0; ray < n_rays; ++ray) {
    const double* ray_c = c + ray * (n_intervals + 1);
    const double* ray_w = w + ray * n_intervals;
    const double* ray_cp = cp + ray * (n_proposal + 1);
    double* ray_d_wp = d_wp + ray * n_proposal;
    outer_bounds(ray_c, n_intervals, ray_cp, wp + ray * n_proposal, n_proposal, bound.data());
    std::fill(ray_d_wp, ray_d_wp + n_proposal, 0.0);
    for (size_t j = 0; j < n_intervals; ++j) {
      const double excess = std::max(0.0, ray_w[j] - bound[j]);
      if (!(excess > 0.0)) continue;
      // bound_j = cumulative[hi] − cumulative[lo]: ∂bound_j/∂wp_k = 1 for lo ≤ k < hi.
      size_t lo = 0, hi = 0, unused = 0;
      outer_searchsorted(ray_cp, n_proposal + 1, ray_c[j], &lo, &unused);
      outer_searchsorted(ray_cp, n_proposal + 1, ray_c[j + 1], &unused, &hi);
      for (size_t k = lo; k < hi; ++k) ray_d_wp[k] -= grad_scale * 2.0 * excess / (ray_w[j] + kInterlevelEps);
    }
  }
}

double outer_interlevel_loss(const std::vector<double>& ray_loss, size_t n_intervals, double mult) {
  double sum = 0.0;
  for (double v : ray_loss) sum += v;
  return mult * sum / (static_cast<double>(ray_loss.size()) * static_cast<double>(n_intervals));
}

}  // namespace mipnerf::ref
