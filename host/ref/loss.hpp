// CPU reference of kernels/loss.cl, in double: the official mip-NeRF per-level loss and its gradient.
#pragma once

#include <cstddef>

namespace mipnerf::ref {

// Sums per group, as kernels/loss.cl writes them (LOSS_SUM_* there).
enum LossSum : size_t { loss_sum_weighted = 0, loss_sum_plain = 1, loss_sums = 2 };

// The data term, as kernels/loss.cl's CHARBONNIER_LOSS / CHARBONNIER_PADDING and LOSS_CHANNEL_MEAN (ops::LossOptions):
// each channel's term is √(residual² + p²) when charbonnier_padding = p > 0, residual² when 0; the channel sum is
// divided by 3 when channel_mean.
struct DataLossOptions {
  double charbonnier_padding = 0.0;
  bool channel_mean = false;
};

// Mirrors loss_fwd_bwd for one level and one chunk of n_rays rays (official train.py):
//   loss_level = Σ_r lossmult_r · Σ_c (comp_rgb − target_rgb)² / Σ_r lossmult_r
//   d_comp_rgb[r][c] = 2 · level_weight · lossmult_r · (comp_rgb[r][c] − target_rgb[r][c]) · inv_lossmult_sum
// comp_rgb [n_rays][3] and d_comp_rgb [n_rays][3] are chunk-local; target_rgb [batch][3] and lossmult
// [batch] are read at batch_offset + r. lossmult == nullptr means every ray weighs 1 (MULTISCALE_LOSS 0).
// partials [groups][2]: the rays of group g (rays g·group_size .. g·group_size + group_size − 1 of the
// chunk) add into partials[first_group + g][loss_sum_weighted] Σ lossmult·Σ_c term (DataLossOptions) and into
// [loss_sum_plain] Σ_c residual², overwriting what was there. group_size mirrors LOSS_GROUP_SIZE.
void loss_fwd_bwd(const double* comp_rgb, const double* target_rgb, const double* lossmult, double level_weight,
                  double inv_lossmult_sum, double* d_comp_rgb, double* partials, size_t first_group,
                  size_t batch_offset, size_t n_rays, size_t group_size, const DataLossOptions& data = {});

// Mirrors loss_reduce: sums[2·out_slot + k] = Σ_g partials[g][k] for g < n_groups, in index order.
void loss_reduce(const double* partials, size_t n_groups, double* sums, size_t out_slot);

}  // namespace mipnerf::ref
