// Loss stage: the photometric loss of one level (official mip-NeRF train.py) and its gradient w.r.t.
// the composited colour, fused in one pass, plus a deterministic reduction of the per-group sums.
//
// For one level, over the whole training batch (official train.py, `losses`):
//   loss_level = Σ_r lossmult_r · Σ_c (comp_rgb[r][c] − target_rgb[r][c])²  /  Σ_r lossmult_r
// The channel sum sits in the numerator and only rays in the denominator, so with lossmult = 1 this is
// 3 × the per-channel MSE (the official code's convention, kept so its λ and learning rates carry over).
//   total = Σ_levels level_weight · loss_level   (level_weight = λ = 0.1 on coarse, 1 on fine)
//   ∂total/∂comp_rgb[r][c] = 2 · level_weight · lossmult_r · (comp_rgb − target_rgb) / Σ_r lossmult_r
//
// The batch is processed in chunks of rays, so the normaliser 1/Σ lossmult of the WHOLE batch is an
// argument (the host knows it before the chunks run). The loss value is reduced without atomics: each
// work-group writes its own sums to `partials`, in a fixed tree order, and loss_reduce (or the host, in
// double) adds the groups in index order. Results depend on the chunking only through float rounding,
// and not at all when chunk sizes are multiples of LOSS_GROUP_SIZE (the groups are then the same).
//
// The data term and its normalisation, compile-time options (a scene pays only for the one it uses):
//   CHARBONNIER_LOSS = 1 with CHARBONNIER_PADDING = p (a float): each channel's term is √(residual² + p²)
//     (mip-NeRF 360's and Zip-NeRF's data loss, multinerf and camp_zipnerf train_utils.compute_data_loss,
//     charb_padding 0.001) instead of residual²; its derivative residual / √(residual² + p²) is bounded by 1, so a
//     large residual pulls no harder than a small one.
//   LOSS_CHANNEL_MEAN = 1: the channel sum is divided by 3, the per-channel mean over the batch that multinerf and
//     camp_zipnerf take (their denominator Σ lossmult counts each channel), which sets the data term's weight against
//     their interlevel and distortion losses. 0: google/mipnerf's channel sum, as above.
// LOSS_SUM_PLAIN stays Σ residual² in every case: the MSE and PSNR a person reads.
//
// Non-finite inputs are not masked: a NaN or Inf in comp_rgb or target_rgb makes that ray's gradient and
// its group's sums NaN/Inf, so the batch's loss is non-finite and the host can detect it and skip the step.

// MULTISCALE_LOSS (0/1): read the per-ray loss multiplier (multiscale datasets weight each pixel by its
// footprint area). 0: every ray weighs 1 and `lossmult` is never read (the host may pass a null buffer).
#ifndef MULTISCALE_LOSS
#define MULTISCALE_LOSS 0
#endif

#ifndef CHARBONNIER_LOSS
#define CHARBONNIER_LOSS 0
#endif
#if CHARBONNIER_LOSS && !defined(CHARBONNIER_PADDING)
#error "CHARBONNIER_LOSS needs CHARBONNIER_PADDING (the official charb_padding, e.g. 0.001f)"
#endif
#ifndef LOSS_CHANNEL_MEAN
#define LOSS_CHANNEL_MEAN 0
#endif
#if LOSS_CHANNEL_MEAN
#define LOSS_CHANNEL_SCALE (1.0f / 3.0f)
#else
#define LOSS_CHANNEL_SCALE 1.0f
#endif

// Work-items per group, a power of two; the host sets it and launches with exactly this local size.
#ifndef LOSS_GROUP_SIZE
#define LOSS_GROUP_SIZE 64
#endif
#if LOSS_GROUP_SIZE < 1 || (LOSS_GROUP_SIZE & (LOSS_GROUP_SIZE - 1)) != 0
#error "LOSS_GROUP_SIZE must be a power of two (the tree reduction halves it)"
#endif

// Sums each group writes, at partials[group][LOSS_SUM_*].
#define LOSS_SUM_WEIGHTED 0 /* Σ lossmult_r · Σ_c term (residual², or Charbonnier's): loss_level's numerator */
#define LOSS_SUM_PLAIN 1    /* Σ Σ_c (comp − target)², unweighted: the true per-channel MSE is this / (3R) */
#define LOSS_SUMS 2

// One level, one chunk of n_rays rays.
//   comp_rgb    [n_rays][3]   composited colour of this level, chunk-local
//   target_rgb  [batch][3]    ground truth (linear, [0,1]); ray i of the chunk is batch_offset + i
//   lossmult    [batch]       per-ray loss weight (read only when MULTISCALE_LOSS), at batch_offset + i
//   level_weight              λ for the coarse level, 1 for the fine one
//   inv_lossmult_sum          1 / Σ lossmult over the whole batch (= 1 / batch size without multiscale)
//   d_comp_rgb  [n_rays][3]   out: ∂total/∂comp_rgb, chunk-local
//   partials    [groups][2]   out: this chunk's groups at first_group, first_group + 1, ...
// Launched over round_up(n_rays, LOSS_GROUP_SIZE) items with local size LOSS_GROUP_SIZE. Items past
// n_rays add zero; there is no early return, because every item must reach the barriers below.
__kernel __attribute__((reqd_work_group_size(LOSS_GROUP_SIZE, 1, 1))) void loss_fwd_bwd(
    __global const float* comp_rgb, __global const float* target_rgb, __global const float* lossmult,
    const float level_weight, const float inv_lossmult_sum, __global float* d_comp_rgb, __global float* partials,
    const uint first_group, const uint batch_offset, const uint n_rays) {
  __local float weighted_sse[LOSS_GROUP_SIZE];
  __local float plain_sse[LOSS_GROUP_SIZE];
  const uint i = get_global_id(0);
  const uint lane = get_local_id(0);

  float weighted = 0.0f, plain = 0.0f;
  if (i < n_rays) {
    const float3 residual = load3(comp_rgb, i) - load3(target_rgb, batch_offset + i);
#if MULTISCALE_LOSS
    const float mult = lossmult[batch_offset + i];
#else
    const float mult = 1.0f;
#endif
    plain = residual.x * residual.x + residual.y * residual.y + residual.z * residual.z;
#if CHARBONNIER_LOSS
    // √(r² + p²) and its derivative r / √(r² + p²): one square root per channel serves both.
    const float3 root = sqrt(residual * residual + CHARBONNIER_PADDING * CHARBONNIER_PADDING);
    weighted = mult * LOSS_CHANNEL_SCALE * (root.x + root.y + root.z);
    const float grad_scale = level_weight * inv_lossmult_sum * mult * LOSS_CHANNEL_SCALE;
    store3(d_comp_rgb, i, grad_scale * (residual / root));
#else
    weighted = mult * LOSS_CHANNEL_SCALE * plain;
    const float grad_scale = 2.0f * level_weight * inv_lossmult_sum * mult * LOSS_CHANNEL_SCALE;
    store3(d_comp_rgb, i, grad_scale * residual);
#endif
  }
  weighted_sse[lane] = weighted;
  plain_sse[lane] = plain;
  barrier(CLK_LOCAL_MEM_FENCE);

  // Pairwise tree: a fixed order, so a group's sums do not depend on scheduling, and the float error
  // grows with log2(LOSS_GROUP_SIZE) rather than with the group size.
  for (uint stride = LOSS_GROUP_SIZE / 2; stride > 0; stride >>= 1) {
    if (lane < stride) {
      weighted_sse[lane] += weighted_sse[lane + stride];
      plain_sse[lane] += plain_sse[lane + stride];
    }
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  if (lane == 0) {
    const size_t group = (size_t)first_group + get_group_id(0);
    partials[LOSS_SUMS * group + LOSS_SUM_WEIGHTED] = weighted_sse[0];
    partials[LOSS_SUMS * group + LOSS_SUM_PLAIN] = plain_sse[0];
  }
}

// sums[LOSS_SUMS·out_slot + k] = Σ_g partials[g][k] over groups 0..n_groups−1, added in index order with
// Kahan compensation (the group sums can span thousands of terms; compensation keeps the float result
// within a few ulps of the exact sum whatever the count). One work-item does it: n_groups is small
// (batch / LOSS_GROUP_SIZE), and a single sequential order is what makes the result deterministic.
// NaN and Inf propagate (NaN − NaN in the compensation stays NaN; an Inf sum gives NaN or Inf, both
// non-finite, which is all the host needs to know).
__kernel void loss_reduce(__global const float* partials, const uint n_groups, __global float* sums,
                          const uint out_slot) {
  if (get_global_id(0) != 0) return;
  for (uint k = 0; k < LOSS_SUMS; ++k) {
    float sum = 0.0f, compensation = 0.0f;
    for (uint g = 0; g < n_groups; ++g) {
      const float term = partials[LOSS_SUMS * g + k] - compensation;
      const float next = sum + term;
      compensation = (next - sum) - term;
      sum = next;
    }
    sums[LOSS_SUMS * out_slot + k] = sum;
  }
}
