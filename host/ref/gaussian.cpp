// CPU reference of kernels/gaussian.cl.
#include "ref/gaussian.hpp"

namespace mipnerf::ref {

namespace {
FrustumMoments<double> interval_moments(const GaussianOptions& options, double t0, double t1, double radius) {
  return options.ray_shape == RayShape::cylinder ? cylinder_moments(t0, t1, radius)
                                                 : conical_frustum_moments(t0, t1, radius);
}
}  // namespace

void gaussian_fwd(const GaussianOptions& options, const std::vector<double>& origins,
                  const std::vector<double>& directions, const std::vector<double>& radii,
                  const std::vector<double>& t_edges, std::vector<double>& means, std::vector<double>& covs,
                  size_t n_rays, size_t n_samples) {
  means.assign(3 * n_rays * n_samples, 0.0);
  covs.assign(3 * n_rays * n_samples, 0.0);
  for (size_t ray = 0; ray < n_rays; ++ray) {
    const double* t = t_edges.data() + ray * (n_samples + 1);
    for (size_t i = 0; i < n_samples; ++i) {
      const auto moments = interval_moments(options, t[i], t[i + 1], radii[ray]);
      const size_t row = ray * n_samples + i;
      lift_gaussian(origins.data() + 3 * ray, directions.data() + 3 * ray, moments, means.data() + 3 * row,
                    covs.data() + 3 * row);
    }
  }
}

void gaussian_full_fwd(const GaussianOptions& options, const std::vector<double>& origins,
                       const std::vector<double>& directions, const std::vector<double>& radii,
                       const std::vector<double>& t_edges, std::vector<double>& means, std::vector<double>& covs,
                       std::vector<double>& cov_off, size_t n_rays, size_t n_samples) {
  gaussian_fwd(options, origins, directions, radii, t_edges, means, covs, n_rays, n_samples);
  cov_off.assign(3 * n_rays * n_samples, 0.0);
  for (size_t ray = 0; ray < n_rays; ++ray) {
    const double* t = t_edges.data() + ray * (n_samples + 1);
    for (size_t i = 0; i < n_samples; ++i) {
      covariance_off_diagonal(directions.data() + 3 * ray, interval_moments(options, t[i], t[i + 1], radii[ray]),
                              cov_off.data() + 3 * (ray * n_samples + i));
    }
  }
}

void gaussian_points_fwd(const std::vector<double>& origins, const std::vector<double>& directions,
                         const std::vector<double>& t_edges, std::vector<double>& means, std::vector<double>& covs,
                         size_t n_rays, size_t n_samples) {
  means.assign(3 * n_rays * n_samples, 0.0);
  covs.assign(3 * n_rays * n_samples, 0.0);
  for (size_t ray = 0; ray < n_rays; ++ray) {
    const double* t = t_edges.data() + ray * (n_samples + 1);
    for (size_t i = 0; i < n_samples; ++i) {
      const double t_mid = 0.5 * (t[i] + t[i + 1]);
      for (int a = 0; a < 3; ++a)
        means[3 * (ray * n_samples + i) + a] = origins[3 * ray + a] + t_mid * directions[3 * ray + a];
    }
  }
}

}  // namespace mipnerf::ref
