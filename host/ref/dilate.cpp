// CPU reference of kernels/dilate.cl (see the header).
#include "ref/dilate.hpp"

#include <algorithm>

namespace mipnerf::ref {

void max_dilate_weights_ray(const double* s, const double* w, size_t n_intervals, double dilation, double domain_near,
                            double domain_far, double* s_out, double* w_out) {
  const size_t n = n_intervals;
  if (n == 0) return;  // no histogram, nothing written (as the kernel)
  const double eps_sq = 1.1920928955078125e-07 * 1.1920928955078125e-07;
  std::vector<double> pdf(n), start(n), end(n), knots;
  for (size_t i = 0; i < n; ++i) {
    pdf[i] = w[i] / std::max(eps_sq, s[i + 1] - s[i]);  // weight_to_pdf
    start[i] = s[i] - dilation;
    end[i] = s[i + 1] + dilation;
  }
  knots.assign(s, s + n + 1);
  knots.insert(knots.end(), start.begin(), start.end());
  knots.insert(knots.end(), end.begin(), end.end());
  std::sort(knots.begin(), knots.end());
  for (double& q : knots) q = std::min(std::max(q, domain_near), domain_far);
  std::vector<double> weights(3 * n);
  double sum = 0;
  for (size_t k = 0; k < 3 * n; ++k) {
    double pooled = 0;
    for (size_t i = 0; i < n; ++i) {
      if (start[i] <= knots[k] && end[i] > knots[k]) pooled = std::max(pooled, pdf[i]);
    }
    weights[k] = pooled * (knots[k + 1] - knots[k]);  // pdf_to_weight
    sum += weights[k];
  }
  for (double& x : weights) x /= std::max(eps_sq, sum);
  std::copy(knots.begin() + 1, knots.end() - 1, s_out);
  std::copy(weights.begin() + 1, weights.end() - 1, w_out);
}

void max_dilate_weights_fwd(const std::vector<double>& s_edges, const std::vector<double>& weights, double dilation,
                            double domain_near, double domain_far, std::vector<double>& s_out,
                            std::vector<double>& w_out, size_t n_rays, size_t n_intervals) {
  const size_t n = n_intervals;
  s_out.assign(n_rays * (3 * n - 1), 0.0);
  w_out.assign(n_rays * (3 * n - 2), 0.0);
  for (size_t ray = 0; ray < n_rays; ++ray) {
    max_dilate_weights_ray(&s_edges[ray * (n + 1)], &weights[ray * n], n, dilation, domain_near, domain_far,
                           &s_out[ray * (3 * n - 1)], &w_out[ray * (3 * n - 2)]);
  }
}

}  // namespace mipnerf::ref
