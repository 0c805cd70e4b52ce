// CPU reference of kernels/gaussian.cl.
#include "ref/gaussian.hpp"

namespace mipnerf::ref {

void gaussian_fwd(const GaussianOptions& options, const std::vector<double>& origins,
                  const std::vector<double>& directions, const std::vector<double>& radii,
                  const std::vector<double>& t_edges, std::vector<double>& means, std::vector<double>& covs,
                  size_t n_rays, size_t n_samples) {
  means.assign(3 * n_rays * n_samples, 0.0);
  covs.assign(3 * n_rays * n_samples, 0.0);
  for (size_t ray = 0; ray < n_rays; ++ray) {
    const double* t = t_edges.data() + ray * (n_samples + 1);
    for (size_t i = 0; i < n_samples; ++i) {
      const auto moments = options.ray_shape == RayShape::cylinder
                               ? cylinder_moments(t[i], t[i + 1], radii[ray])
                               : conical_frustum_moments(t[i], t[i + 1], radii[ray]);
      const size_t row = ray * n_samples + i;
      lift_gaussian(origins.data() + 3 * ray, directions.data() + 3 * ray, moments, means.data() + 3 * row,
                    covs.data() + 3 * row);
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
