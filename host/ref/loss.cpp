// CPU reference of kernels/loss.cl, in double.
#include "ref/loss.hpp"

#include <cmath>

namespace mipnerf::ref {

void loss_fwd_bwd(const double* comp_rgb, const double* target_rgb, const double* lossmult, double level_weight,
                  double inv_lossmult_sum, double* d_comp_rgb, double* partials, size_t first_group,
                  size_t batch_offset, size_t n_rays, size_t group_size, const DataLossOptions& data) {
  const double channel_scale = data.channel_mean ? 1.0 / 3.0 : 1.0;
  const double padding = data.charbonnier_padding;
  const size_t n_groups = (n_rays + group_size - 1) / group_size;
  for (size_t g = 0; g < n_groups; ++g) {
    double weighted = 0.0, plain = 0.0;
    for (size_t r = g * group_size; r < n_rays && r < (g + 1) * group_size; ++r) {
      const size_t b = batch_offset + r;
      const double mult = lossmult ? lossmult[b] : 1.0;
      double squared = 0.0, term = 0.0;
      for (size_t c = 0; c < 3; ++c) {
        const double residual = comp_rgb[3 * r + c] - target_rgb[3 * b + c];
        squared += residual * residual;
        // d/dr of r² is 2r; of √(r² + p²) it is r / √(r² + p²)
        double d_term = 2.0 * residual;
        if (padding > 0.0) {
          const double root = std::sqrt(residual * residual + padding * padding);
          term += root;
          d_term = residual / root;
        } else {
          term += residual * residual;
        }
        d_comp_rgb[3 * r + c] = level_weight * inv_lossmult_sum * mult * channel_scale * d_term;
      }
      plain += squared;
      weighted += mult * channel_scale * term;
    }
    partials[loss_sums * (first_group + g) + loss_sum_weighted] = weighted;
    partials[loss_sums * (first_group + g) + loss_sum_plain] = plain;
  }
}

void loss_reduce(const double* partials, size_t n_groups, double* sums, size_t out_slot) {
  for (size_t k = 0; k < loss_sums; ++k) {
    double sum = 0.0;
    for (size_t g = 0; g < n_groups; ++g) sum += partials[loss_sums * g + k];
    sums[loss_sums * out_slot + k] = sum;
  }
}

}  // namespace mipnerf::ref
