// CPU reference of kernels/encode.cl.
#include "ref/encode.hpp"

#include "ref/gaussian.hpp"

namespace mipnerf::ref {
namespace {

// Writes a row's 3L sines at out[0..3L) and 3L cosines at out[3L..6L).
void encode_row(const EncodingOptions& options, const double* mean, const double* var, double* out) {
  const int n_degrees = options.degrees();
  for (int l = 0; l < n_degrees; ++l) {
    for (int a = 0; a < 3; ++a) {
      ipe_pair(mean[a], var ? var[a] : 0.0, options.min_deg + l, out[3 * l + a], out[3 * (n_degrees + l) + a]);
    }
  }
}

}  // namespace

void ipe_fwd(const EncodingOptions& options, const std::vector<double>& means, const std::vector<double>& covs,
             std::vector<double>& features, size_t n_rows) {
  const size_t width = options.ipe_width();
  features.assign(n_rows * width, 0.0);
  for (size_t row = 0; row < n_rows; ++row) {
    encode_row(options, means.data() + 3 * row, covs.data() + 3 * row, features.data() + row * width);
  }
}

void pe_fwd(const EncodingOptions& options, const std::vector<double>& x, std::vector<double>& features,
            size_t n_rows) {
  const size_t width = options.pe_width(), identity = options.append_identity ? 3 : 0;
  features.assign(n_rows * width, 0.0);
  for (size_t row = 0; row < n_rows; ++row) {
    double* out = features.data() + row * width;
    for (size_t a = 0; a < identity; ++a) out[a] = x[3 * row + a];
    encode_row(options, x.data() + 3 * row, nullptr, out + identity);
  }
}

void gaussian_ipe_fwd(const GaussianOptions& gaussian_options, const EncodingOptions& options,
                      const std::vector<double>& origins, const std::vector<double>& directions,
                      const std::vector<double>& radii, const std::vector<double>& t_edges,
                      std::vector<double>& features, size_t n_rays, size_t n_samples) {
  std::vector<double> means, covs;
  gaussian_fwd(gaussian_options, origins, directions, radii, t_edges, means, covs, n_rays, n_samples);
  ipe_fwd(options, means, covs, features, n_rays * n_samples);
}

}  // namespace mipnerf::ref
