// Host wrapper of kernels/loss.cl: the per-level photometric loss, its gradient, and the loss report.
//
// Convention (official mip-NeRF train.py, kept exactly so λ and learning rates carry over):
//   loss_level = Σ_rays lossmult_r · Σ_channels (comp_rgb − target)² / Σ_rays lossmult_r
// (LossOptions: Charbonnier's term instead of the square, and the channel mean instead of the sum, for the models
// whose official code takes them: mip-NeRF 360, Zip-NeRF.)
//   total      = Σ_levels weight_level · loss_level,  weight = λ (0.1) on coarse, 1 on fine
// The channel sum is not divided by 3: with lossmult = 1, loss_level = 3 × the per-channel MSE. What a
// person reads (progress bar, CSV) is LevelLoss::mse() and psnr(): the true per-channel MSE, unweighted.
#pragma once

#include <cstddef>
#include <vector>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "cl/program.hpp"

namespace mipnerf::ops {

// Compile-time options of loss.cl.
struct LossOptions {
  // MULTISCALE_LOSS: weight each ray by its lossmult (multiscale datasets: the pixel's footprint area
  // relative to full resolution). Off: every ray weighs 1 and the lossmult buffer is never read.
  bool multiscale = false;
  // CHARBONNIER_LOSS / CHARBONNIER_PADDING: each channel's term is √(residual² + p²) with p = charbonnier_padding
  // (mip-NeRF 360's and Zip-NeRF's data loss, official charb_padding 0.001) when > 0; residual² when 0.
  float charbonnier_padding = 0.0f;
  // LOSS_CHANNEL_MEAN: the channel sum divided by 3 (multinerf's and camp_zipnerf's per-channel mean, which sets the
  // data term's weight against their interlevel and distortion losses); off: google/mipnerf's channel sum.
  bool channel_mean = false;
};

// The build options for `options` with work-groups of `group_size` (a power of two).
ocl::BuildOptions loss_build_options(const LossOptions& options, size_t group_size);

// The weight of level `level` of `n_levels` in the total, as train.py: coarse_weight (λ, paper 0.1) on
// every level but the last, 1 on the last.
float loss_level_weight(size_t level, size_t n_levels, float coarse_weight = 0.1f);

// Per level and step: what the kernel needs besides buffers. lossmult_sum is Σ lossmult over the WHOLE
// batch (the batch size without multiscale), known before the chunks run.
struct LossLevelArgs {
  float level_weight = 1.0f;
  double lossmult_sum = 0.0;
};

// Where one chunk sits: its rays are batch rays batch_offset .. batch_offset + n_rays − 1; its groups'
// sums go to partials slots first_group .. first_group + groups_for(n_rays) − 1.
struct LossChunk {
  size_t n_rays = 0;
  size_t batch_offset = 0;
  size_t first_group = 0;
};

// One level's sums over the batch, reduced from the partials, and what the host reports from them.
struct LevelLoss {
  double weighted_sse = 0.0;  // Σ_r lossmult_r · Σ_c residual² (the data term of LossOptions: LOSS_SUM_WEIGHTED)
  double plain_sse = 0.0;     // Σ_r Σ_c residual² (unweighted)
  double lossmult_sum = 0.0;  // Σ_r lossmult_r over the batch
  size_t n_rays = 0;          // rays in the batch
  // A proposal round (Zip-NeRF) has no colour: its loss is the spline interlevel loss, mult already applied
  // (ops::interlevel_loss_value); the photometric sums above stay 0.
  bool proposal = false;
  double interlevel = 0.0;
  // The last level's distortion loss (mip-NeRF 360 eq. 15), mult already applied (ops::distortion_loss_value); 0
  // without one. Not in loss(): total_loss adds it.
  double distortion = 0.0;

  // The official per-level loss: weighted_sse / lossmult_sum (= 3 × per-channel MSE when lossmult = 1; the data term
  // of LossOptions otherwise), or a proposal round's interlevel loss.
  double loss() const { return proposal ? interlevel : weighted_sse / lossmult_sum; }
  // The true per-channel MSE over the batch's pixels, unweighted: plain_sse / (3 · n_rays).
  double mse() const { return plain_sse / (3.0 * static_cast<double>(n_rays)); }
  // PSNR of mse() for values in [0, 1]: −10 · log10(mse). (train.py logs −10·log10(loss), which reads
  // 10·log10(3) ≈ 4.77 dB low; we report the per-channel figure, comparable to eval PSNR.)
  double psnr() const;
  // False when a NaN or Inf reached the sums (a non-finite colour or target in the batch).
  bool finite() const;
};

// Adds [n_groups][2] partial sums (as downloaded from the partials buffer) in double, in index order.
LevelLoss sum_loss_partials(const std::vector<float>& partials, size_t n_groups, double lossmult_sum,
                            size_t n_rays);

// Σ_levels loss_level_weight(l) · levels[l].loss(), with coarse_weight = λ; a proposal round's loss counts once (its
// mult is inside it), and the last colour level is the one loss_level_weight weighs 1.
double total_loss(const std::vector<LevelLoss>& levels, float coarse_weight = 0.1f);

// The loss stage on one device, one specialisation. Arguments of each kernel are set in one place.
class Loss {
 public:
  Loss(ocl::Context& ctx, const LossOptions& options);

  const LossOptions& options() const { return options_; }
  // Work-items per group (LOSS_GROUP_SIZE): each group of this many rays writes one partials slot.
  size_t group_size() const { return group_size_; }
  // Partials slots a chunk of n_rays writes: ceil(n_rays / group_size()).
  size_t groups_for(size_t n_rays) const { return (n_rays + group_size_ - 1) / group_size_; }

  // Enqueues loss_fwd_bwd for one level and one chunk (asynchronous, in queue order):
  //   comp_rgb [chunk][3] → d_comp_rgb [chunk][3] = ∂total/∂comp_rgb, chunk-local;
  //   target_rgb [batch][3], lossmult [batch] (nullptr allowed unless options().multiscale);
  //   partials [slots][2]: the chunk's group sums at chunk.first_group onwards.
  // Throws mipnerf::Error for a buffer too small, a missing lossmult, or a lossmult_sum that is not > 0.
  void fwd_bwd(const ocl::DeviceArray<float>& comp_rgb, const ocl::DeviceArray<float>& target_rgb,
               const ocl::DeviceArray<float>* lossmult, const LossLevelArgs& level,
               ocl::DeviceArray<float>& d_comp_rgb, ocl::DeviceArray<float>& partials, const LossChunk& chunk);

  // Enqueues loss_reduce: sums[2·out_slot + k] = Σ partials[g][k] over g < n_groups, one fixed order
  // (device alternative to sum_loss_partials, e.g. to keep a step's loss on the device).
  void reduce(const ocl::DeviceArray<float>& partials, size_t n_groups, ocl::DeviceArray<float>& sums,
              size_t out_slot);

 private:
  ocl::Context* ctx_;
  LossOptions options_;
  size_t group_size_;
  ::cl::Kernel* fwd_bwd_;
  ::cl::Kernel* reduce_;
};

}  // namespace mipnerf::ops
