// CPU reference of kernels/sample.cl.
#include "ref/sample.hpp"

#include <algorithm>

#include "core/rng.hpp"

namespace mipnerf::ref {
namespace {

// The kernel's guard too: in disparity, a term of weight 0 is left out, so a zero bound gives the formula's limit
// (0 wherever its term has weight) where the official 1/near·(1 − s) + 1/far·s makes ∞·0 = NaN (kernels/sample.cl).
double stratified_edge(bool lindisp, double near, double far, size_t k, size_t n_samples) {
  const double s = static_cast<double>(k) / static_cast<double>(n_samples);
  if (!lindisp) return near * (1.0 - s) + far * s;
  const double near_term = s < 1.0 ? (1.0 - s) / near : 0.0;
  const double far_term = s > 0.0 ? s / far : 0.0;
  return 1.0 / (near_term + far_term);
}

}  // namespace

void sample_stratified_fwd(const SampleOptions& options, const std::vector<double>& near,
                           const std::vector<double>& far, std::vector<double>& t_edges, size_t n_rays,
                           size_t n_samples, const RngKey& key) {
  const size_t n_edges = n_samples + 1;
  t_edges.assign(n_rays * n_edges, 0.0);
  for (size_t ray = 0; ray < n_rays; ++ray) {
    const auto edge = [&](size_t k) { return stratified_edge(options.lindisp, near[ray], far[ray], k, n_samples); };
    for (size_t k = 0; k < n_edges; ++k) {
      double t = edge(k);
      if (options.randomized) {
        const double lower = k == 0 ? t : 0.5 * (edge(k - 1) + t);
        const double upper = k == n_samples ? t : 0.5 * (t + edge(k + 1));
        const auto u = rng_uniform4(key.seed, key.first_ray + static_cast<uint32_t>(ray), key.step,
                                    static_cast<uint32_t>(k / 4), rng_stream_stratified);
        t = lower + (upper - lower) * u[k % 4];
      }
      t_edges[ray * n_edges + k] = t;
    }
  }
}

void sample_merge_fwd(const std::vector<double>& t_a, const std::vector<double>& t_b, std::vector<double>& t_out,
                      size_t n_rays, size_t len_a, size_t len_b) {
  t_out.assign(n_rays * (len_a + len_b), 0.0);
  for (size_t ray = 0; ray < n_rays; ++ray) {
    std::merge(t_a.begin() + ray * len_a, t_a.begin() + (ray + 1) * len_a, t_b.begin() + ray * len_b,
               t_b.begin() + (ray + 1) * len_b, t_out.begin() + ray * (len_a + len_b));
  }
}

}  // namespace mipnerf::ref
