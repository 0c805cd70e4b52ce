// CPU reference of kernels/sample_intervals.cl.
#include "ref/sample_intervals.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/rng.hpp"

namespace mipnerf::ref {

namespace {

constexpr double kFloatEps = std::numeric_limits<float>::epsilon();  // official jnp.finfo(jnp.float32).eps
constexpr double kInf = std::numeric_limits<double>::infinity();

double clip_to_domain(const SampleIntervalsOptions& options, double s) {
  return std::min(std::max(s, static_cast<double>(options.domain_near)), static_cast<double>(options.domain_far));
}

// The leftmost point where the piecewise-linear CDF reaches u (its lower inverse; the official's is the rightmost).
double invert_leftmost(const std::vector<double>& cdf, const double* s, double u) {
  const size_t n = cdf.size() - 1;
  // The first k with cdf_{k+1} ≥ u: interval k holds the first point at level u.
  size_t k = static_cast<size_t>(std::lower_bound(cdf.begin() + 1, cdf.end(), u) - (cdf.begin() + 1));
  k = std::min(k, n - 1);
  const double step = cdf[k + 1] - cdf[k];
  const double frac = step > 0.0 ? std::clamp((u - cdf[k]) / step, 0.0, 1.0) : 0.0;
  return s[k] + frac * (s[k + 1] - s[k]);
}

}  // namespace

std::vector<double> sample_intervals_logits(const SampleIntervalsOptions& options, const double* s, const double* w,
                                            size_t n) {
  std::vector<double> logits(n);
  const double tiny = std::numeric_limits<float>::min(), huge = std::numeric_limits<float>::max();
  for (size_t i = 0; i < n; ++i) {
    // safe_log clips to [tiny, max] (so w + padding = 0 is log(FLT_MIN), finite); empty intervals are −∞.
    logits[i] =
        s[i + 1] > s[i] ? options.anneal * std::log(std::clamp(w[i] + options.resample_padding, tiny, huge)) : -kInf;
  }
  return logits;
}

std::vector<double> sample_intervals_cdf(const std::vector<double>& logits) {
  const size_t n = logits.size();
  const double max_logit = *std::max_element(logits.begin(), logits.end());
  if (max_logit == -kInf) return {};
  std::vector<double> p(n);
  double sum = 0.0;
  for (size_t i = 0; i < n; ++i) sum += p[i] = std::exp(logits[i] - max_logit);  // jax.nn.softmax's shift
  std::vector<double> cdf(n + 1);
  cdf[0] = 0.0;
  double partial = 0.0;
  for (size_t k = 1; k < n; ++k) {
    partial += p[k - 1] / sum;
    cdf[k] = std::min(1.0, partial);
  }
  cdf[n] = 1.0;
  return cdf;
}

std::vector<double> sample_intervals_u(const SampleIntervalsOptions& options, size_t n_new, const RngKey& key,
                                       size_t ray) {
  std::vector<double> u(n_new);
  const double m = static_cast<double>(n_new);
  const double eps = kFloatEps;
  const uint32_t item = key.first_ray + static_cast<uint32_t>(ray);
  const double u_max = eps + (1.0 - eps) / m;
  const double max_jitter = (1.0 - u_max) / (m - 1.0) - eps;
  const double pad = 1.0 / (2.0 * m);
  for (size_t j = 0; j < n_new; ++j) {
    if (!options.randomized) {
      u[j] = pad + static_cast<double>(j) * (1.0 - pad - eps - pad) / (m - 1.0);  // linspace(pad, 1 − pad − ε, M)
      continue;
    }
    const size_t slot = options.single_jitter ? 0 : j;
    const double xi =
        rng_uniform4(key.seed, item, key.step, static_cast<uint32_t>(slot / 4), rng_stream_proposal)[slot % 4];
    u[j] = static_cast<double>(j) * (1.0 - u_max) / (m - 1.0) + xi * max_jitter;
  }
  return u;
}

double sample_intervals_invert(const std::vector<double>& cdf, const double* s, double u) {
  const size_t n = cdf.size() - 1;
  // searchsorted(cdf, u, 'right') − 1, at most n − 1 (cdf_n = 1 > u).
  size_t k = static_cast<size_t>(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin());
  k = std::min(std::max<size_t>(k, 1) - 1, n - 1);
  const double eps_sq = kFloatEps * kFloatEps;  // sorted_interp's guard
  const double frac = std::clamp((u - cdf[k]) / std::max(eps_sq, cdf[k + 1] - cdf[k]), 0.0, 1.0);
  return s[k] + frac * (s[k + 1] - s[k]);
}

std::vector<double> sample_intervals_edges(const SampleIntervalsOptions& options, const std::vector<double>& c) {
  const size_t m = c.size();
  std::vector<double> edges(m + 1);
  for (size_t j = 1; j < m; ++j) edges[j] = (c[j - 1] + c[j]) / 2.0;
  edges[0] = 2.0 * c[0] - edges[1];          // the first midpoint reflected about the first centre
  edges[m] = 2.0 * c[m - 1] - edges[m - 1];  // the last about the last
  for (auto& e : edges) e = clip_to_domain(options, e);
  return edges;
}

std::vector<double> sample_intervals_ray(const SampleIntervalsOptions& options, const double* s, const double* w,
                                         size_t n, const std::vector<double>& u) {
  const std::vector<double> cdf = sample_intervals_cdf(sample_intervals_logits(options, s, w, n));
  if (cdf.empty()) return std::vector<double>(u.size() + 1, clip_to_domain(options, s[0]));
  std::vector<double> centres(u.size());
  for (size_t j = 0; j < u.size(); ++j) centres[j] = sample_intervals_invert(cdf, s, u[j]);
  return sample_intervals_edges(options, centres);
}

void sample_intervals_fwd(const SampleIntervalsOptions& options, const std::vector<double>& s_edges,
                          const std::vector<double>& weights, std::vector<double>& s_new, size_t n_rays,
                          size_t n_intervals, size_t n_new, const RngKey& key) {
  const size_t n = n_intervals, n_out = n_new + 1;
  s_new.assign(n_rays * n_out, 0.0);
  if (n == 0 || n_new < 2) return;
  for (size_t ray = 0; ray < n_rays; ++ray) {
    const auto edges = sample_intervals_ray(options, s_edges.data() + ray * (n + 1), weights.data() + ray * n, n,
                                            sample_intervals_u(options, n_new, key, ray));
    std::copy(edges.begin(), edges.end(), s_new.begin() + static_cast<std::ptrdiff_t>(ray * n_out));
  }
}

double ray_distance_s_to_t(RayDistance ray_distance, double s, double near, double far) {
  if (ray_distance == RayDistance::linear) return std::clamp(s * far + (1.0 - s) * near, near, far);
  if (ray_distance == RayDistance::reciprocal) return std::clamp(1.0 / (s / far + (1.0 - s) / near), near, far);
  const auto h = [](double t) { return std::pow(1.0 + 2.0 * t / 2.5, -1.5); };
  // The official's float32 constants (kernels/sample_intervals.cl): |p − 1|/p and p/|p − 1| rounded to float32, their
  // product κ; inv_power_ladder's clip at y_max = nextafter(float32 of the limit, −∞).
  const double forward = static_cast<double>(2.5f / -1.5f), inverse = static_cast<double>(-1.5f / 2.5f);
  const double kappa_minus_1 = forward * inverse - 1.0;
  const double y_max = std::nextafter(static_cast<float>(-forward), -std::numeric_limits<float>::infinity());
  const double min_g = inverse * y_max + 1.0;
  const double g_exact = s * h(far) + (1.0 - s) * h(near);
  const double g = std::max(g_exact - kappa_minus_1 * (1.0 - g_exact), min_g);
  return std::clamp(1.25 * (std::pow(g, -2.0 / 3.0) - 1.0), near, far);
}

void sample_intervals_s_to_t(const std::vector<double>& s, const std::vector<double>& near,
                             const std::vector<double>& far, std::vector<double>& t, size_t n_rays, size_t n_per_ray,
                             RayDistance ray_distance) {
  t.assign(n_rays * n_per_ray, 0.0);
  for (size_t i = 0; i < n_rays * n_per_ray; ++i) {
    const size_t ray = i / n_per_ray;
    t[i] = ray_distance_s_to_t(ray_distance, s[i], near[ray], far[ray]);
  }
}

double ray_distance_power_ladder_float32_bound(double t) {
  return 32.0 * std::ldexp(1.0, -23) * (std::abs(t) + 1.25);
}

SampleIntervalsEnvelope sample_intervals_envelope(const SampleIntervalsOptions& options, const double* s,
                                                  const double* w, size_t n, const std::vector<double>& u, double eps,
                                                  double u_slack) {
  const size_t m = u.size();
  SampleIntervalsEnvelope env;
  double s_abs = 0.0;
  for (size_t i = 0; i <= n; ++i) s_abs = std::max(s_abs, std::abs(s[i]));
  const std::vector<double> logits = sample_intervals_logits(options, s, w, n);
  const std::vector<double> cdf = sample_intervals_cdf(logits);
  if (cdf.empty()) {
    const double point = clip_to_domain(options, s[0]);
    env.lo.assign(m + 1, point);
    env.hi.assign(m + 1, point);
    return env;
  }
  // δ_cdf from the softmax's relative errors (the header's derivation).
  const double max_logit = *std::max_element(logits.begin(), logits.end());
  double sum = 0.0;
  for (double l : logits) sum += std::exp(l - max_logit);
  double weighted_relative = 0.0;  // Σ p_i r_i
  for (double l : logits) {
    if (l == -kInf) continue;
    const double r = eps * (options.anneal + 4.0 * std::abs(l)) + eps * std::abs(l - max_logit) + 3.0 * eps;
    weighted_relative += std::exp(l - max_logit) / sum * r;
  }
  const double delta = 2.0 * weighted_relative + (2.0 * static_cast<double>(n) + 1.0) * eps + 6.0 * eps + u_slack;
  env.cdf_error = delta;
  std::vector<double> c_lo(m), c_hi(m);
  const double centre_rounding = 8.0 * eps * s_abs;
  for (size_t j = 0; j < m; ++j) {
    c_lo[j] = invert_leftmost(cdf, s, std::max(0.0, u[j] - delta)) - centre_rounding;
    // The rightmost point at u + δ: the official's own inverse (last k with cdf_k ≤ u), capped at the last edge.
    c_hi[j] = std::min(u[j] + delta, 1.0) >= 1.0 ? s[n] : sample_intervals_invert(cdf, s, u[j] + delta);
    c_hi[j] += centre_rounding;
  }
  env.lo.resize(m + 1);
  env.hi.resize(m + 1);
  const double edge_rounding = 2.0 * eps * s_abs;
  for (size_t j = 1; j < m; ++j) {
    env.lo[j] = (c_lo[j - 1] + c_lo[j]) / 2.0 - edge_rounding;
    env.hi[j] = (c_hi[j - 1] + c_hi[j]) / 2.0 + edge_rounding;
  }
  env.lo[0] = 1.5 * c_lo[0] - 0.5 * c_hi[1] - edge_rounding;
  env.hi[0] = 1.5 * c_hi[0] - 0.5 * c_lo[1] + edge_rounding;
  env.lo[m] = 1.5 * c_lo[m - 1] - 0.5 * c_hi[m - 2] - edge_rounding;
  env.hi[m] = 1.5 * c_hi[m - 1] - 0.5 * c_lo[m - 2] + edge_rounding;
  for (size_t j = 0; j <= m; ++j) {
    env.lo[j] = clip_to_domain(options, env.lo[j]);
    env.hi[j] = clip_to_domain(options, env.hi[j]);
  }
  return env;
}

}  // namespace mipnerf::ref
