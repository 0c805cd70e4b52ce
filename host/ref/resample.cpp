// CPU reference of kernels/resample.cl.
#include "ref/resample.hpp"

#include <algorithm>
#include <limits>

#include "core/rng.hpp"

namespace mipnerf::ref {

std::vector<double> resample_cdf(const ResampleOptions& options, const double* raw, size_t n) {
  std::vector<double> w(n), cdf(n + 1);
  double sum = 0.0;
  for (size_t i = 0; i < n; ++i) {
    if (options.blur) {
      // Official blur-pool: max over each pair of neighbours of the edge-padded weights, then the mean of pairs.
      const double left = raw[i > 0 ? i - 1 : 0], right = raw[i + 1 < n ? i + 1 : n - 1];
      w[i] = 0.5 * (std::max(left, raw[i]) + std::max(raw[i], right));
    } else {
      w[i] = raw[i];
    }
    w[i] += options.padding;
    sum += w[i];
  }
  // Official sorted_piecewise_constant_pdf: pad the sum up to 1e-5 (an all-zero histogram becomes uniform).
  const double extra = std::max(0.0, 1e-5 - sum);
  for (auto& v : w) v += extra / static_cast<double>(n);
  sum += extra;
  cdf[0] = 0.0;
  double partial = 0.0;
  for (size_t k = 1; k < n; ++k) {
    partial += w[k - 1] / sum;
    cdf[k] = std::min(1.0, partial);
  }
  cdf[n] = 1.0;
  return cdf;
}

void resample_fwd(const ResampleOptions& options, const std::vector<double>& t_edges,
                  const std::vector<double>& weights, std::vector<double>& t_new, size_t n_rays, size_t n_samples,
                  size_t n_new, const RngKey& key) {
  const size_t n = n_samples, n_out = n_new + 1;
  const double eps = std::numeric_limits<float>::epsilon();  // official jnp.finfo('float32').eps
  t_new.assign(n_rays * n_out, 0.0);
  if (n == 0 || n_new == 0) return;
  for (size_t ray = 0; ray < n_rays; ++ray) {
    const double* t = t_edges.data() + ray * (n + 1);
    const std::vector<double> cdf = resample_cdf(options, weights.data() + ray * n, n);
    for (size_t j = 0; j < n_out; ++j) {
      double u;
      if (options.randomized) {
        const double stratum = 1.0 / static_cast<double>(n_out);
        const auto xi = rng_uniform4(key.seed, key.first_ray + static_cast<uint32_t>(ray), key.step,
                                     static_cast<uint32_t>(j / 4), rng_stream_resample);
        u = static_cast<double>(j) * stratum + xi[j % 4] * (stratum - eps);
      } else {
        u = static_cast<double>(j) * (1.0 - eps) / static_cast<double>(n_new);
      }
      u = std::min(u, 1.0 - eps);
      // The last k with cdf[k] ≤ u (official: the final True of u >= cdf); cdf[n] = 1 > u bounds it by n − 1.
      const size_t k = static_cast<size_t>(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin()) - 1;
      const double frac = std::clamp((u - cdf[k]) / (cdf[k + 1] - cdf[k]), 0.0, 1.0);
      t_new[ray * n_out + j] = t[k] + frac * (t[k + 1] - t[k]);
    }
  }
}

}  // namespace mipnerf::ref
