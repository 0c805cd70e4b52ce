// CPU reference of kernels/encode.cl.
#include "ref/encode.hpp"

#include <algorithm>
#include <cmath>

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

void gaussian_concat_pe_fwd(const GaussianOptions& gaussian_options, const EncodingOptions& options,
                            const std::vector<double>& origins, const std::vector<double>& directions,
                            const std::vector<double>& radii, const std::vector<double>& t_edges,
                            std::vector<double>& features, size_t n_rays, size_t n_samples) {
  const size_t rows = n_rays * n_samples;
  std::vector<double> means, covs, cov_off, mean_pe;
  gaussian_full_fwd(gaussian_options, origins, directions, radii, t_edges, means, covs, cov_off, n_rays, n_samples);
  pe_fwd(options, means, mean_pe, rows);
  const size_t mean_width = options.pe_width(), width = options.concat_pe_width();
  const int cov_degrees = options.covariance_degrees;
  features.assign(rows * width, 0.0);
  for (size_t row = 0; row < rows; ++row) {
    double* out = features.data() + row * width;
    std::copy(mean_pe.begin() + row * mean_width, mean_pe.begin() + (row + 1) * mean_width, out);
    const double* d = covs.data() + 3 * row;
    const double* o = cov_off.data() + 3 * row;
    const double upper[6] = {d[0], o[0], o[1], d[1], o[2], d[2]};  // xx, xy, xz, yy, yz, zz
    double* cov_pe = out + mean_width;
    for (int l = 0; l < cov_degrees; ++l) {
      for (int e = 0; e < 6; ++e) {
        // sign(Σ) ∘ √|Σ|, with sign(0) = 0 as OpenCL's sign().
        const double signed_sqrt = upper[e] > 0 ? std::sqrt(upper[e]) : upper[e] < 0 ? -std::sqrt(-upper[e]) : 0.0;
        ipe_pair(signed_sqrt, 0.0, l, cov_pe[6 * l + e], cov_pe[6 * (cov_degrees + l) + e]);
      }
    }
  }
}

}  // namespace mipnerf::ref
