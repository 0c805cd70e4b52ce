// Host wrapper of kernels/loss.cl.
#include "ops/loss.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "cl/error.hpp"
#include "cl/launch.hpp"

namespace mipnerf::ops {
namespace {

constexpr size_t kSumsPerGroup = 2;  // LOSS_SUMS in loss.cl

// The largest power of two not above the device's 1-D work-group size: the tree reduction halves it.
size_t choose_group_size(const ocl::Context& ctx) {
  const size_t limit = std::min(ctx.traits().local_size_1d, ctx.device_info().max_work_group_size);
  size_t size = 1;
  while (size * 2 <= limit) size *= 2;
  return size;
}

cl_uint as_uint(size_t value, const char* what) {
  if (value > std::numeric_limits<cl_uint>::max()) {
    throw Error(std::string("loss: ") + what + " = " + std::to_string(value) +
                " exceeds the kernel's 32-bit index; lower the batch or chunk size");
  }
  return static_cast<cl_uint>(value);
}

}  // namespace

ocl::BuildOptions loss_build_options(const LossOptions& options, size_t group_size) {
  if (!(options.charbonnier_padding >= 0.0f) || !std::isfinite(options.charbonnier_padding)) {
    throw Error("loss: charbonnier_padding = " + std::to_string(options.charbonnier_padding) +
                " must be finite and >= 0 (0: the squared error)");
  }
  ocl::BuildOptions built;
  built.define("MULTISCALE_LOSS", options.multiscale ? 1 : 0)
      .define("LOSS_GROUP_SIZE", static_cast<long long>(group_size));
  // Only when on: without them, the build options (and the kernel) as they were.
  if (options.charbonnier_padding > 0.0f) {
    built.define("CHARBONNIER_LOSS", 1).define_float("CHARBONNIER_PADDING", options.charbonnier_padding);
  }
  if (options.channel_mean) built.define("LOSS_CHANNEL_MEAN", 1);
  return built;
}

float loss_level_weight(size_t level, size_t n_levels, float coarse_weight) {
  return level + 1 < n_levels ? coarse_weight : 1.0f;
}

double LevelLoss::psnr() const { return -10.0 * std::log10(mse()); }

bool LevelLoss::finite() const {
  return std::isfinite(weighted_sse) && std::isfinite(plain_sse) && std::isfinite(interlevel);
}

LevelLoss sum_loss_partials(const std::vector<float>& partials, size_t n_groups, double lossmult_sum,
                            size_t n_rays) {
  if (partials.size() < kSumsPerGroup * n_groups) {
    throw Error("loss: " + std::to_string(partials.size()) + " partial sums given for " + std::to_string(n_groups) +
                " groups (needs " + std::to_string(kSumsPerGroup * n_groups) + ")");
  }
  LevelLoss level;
  level.lossmult_sum = lossmult_sum;
  level.n_rays = n_rays;
  for (size_t g = 0; g < n_groups; ++g) {
    level.weighted_sse += partials[kSumsPerGroup * g];
    level.plain_sse += partials[kSumsPerGroup * g + 1];
  }
  return level;
}

double total_loss(const std::vector<LevelLoss>& levels, float coarse_weight) {
  double total = 0.0;
  for (size_t l = 0; l < levels.size(); ++l) {
    const double weight = levels[l].proposal ? 1.0 : loss_level_weight(l, levels.size(), coarse_weight);
    total += weight * levels[l].loss() + levels[l].distortion;
  }
  return total;
}

Loss::Loss(ocl::Context& ctx, const LossOptions& options)
    : ctx_(&ctx), options_(options), group_size_(choose_group_size(ctx)) {
  auto& program = ctx.program({"common.cl", "loss.cl"}, loss_build_options(options_, group_size_));
  fwd_bwd_ = &program.kernel("loss_fwd_bwd");
  reduce_ = &program.kernel("loss_reduce");
  size_t kernel_limit = 0;
  ocl::check(fwd_bwd_->getWorkGroupInfo(ctx.device_info().device, CL_KERNEL_WORK_GROUP_SIZE, &kernel_limit),
             "clGetKernelWorkGroupInfo(loss_fwd_bwd)");
  if (kernel_limit < group_size_) {
    throw Error("loss_fwd_bwd: the device runs at most " + std::to_string(kernel_limit) +
                " work-items per group for this kernel, fewer than its LOSS_GROUP_SIZE " +
                std::to_string(group_size_) + " (device " + ctx.device_info().name + ")");
  }
}

void Loss::fwd_bwd(const ocl::DeviceArray<float>& comp_rgb, const ocl::DeviceArray<float>& target_rgb,
                   const ocl::DeviceArray<float>* lossmult, const LossLevelArgs& level,
                   ocl::DeviceArray<float>& d_comp_rgb, ocl::DeviceArray<float>& partials, const LossChunk& chunk) {
  const std::string where = "loss_fwd_bwd";
  const size_t n = chunk.n_rays;
  if (n == 0) return;
  comp_rgb.require_size(3 * n, where);
  target_rgb.require_size(3 * (chunk.batch_offset + n), where);
  d_comp_rgb.require_size(3 * n, where);
  partials.require_size(kSumsPerGroup * (chunk.first_group + groups_for(n)), where);
  if (options_.multiscale) {
    if (!lossmult) throw Error(where + ": built for a multiscale loss but no lossmult buffer was given");
    lossmult->require_size(chunk.batch_offset + n, where);
  }
  if (!(level.lossmult_sum > 0.0) || !std::isfinite(level.lossmult_sum)) {
    throw Error(where + ": the batch's sum of loss multipliers is " + std::to_string(level.lossmult_sum) +
                "; it must be positive and finite (is every lossmult zero?)");
  }
  if (!std::isfinite(level.level_weight)) throw Error(where + ": the level weight is not finite");
  const float inv_lossmult_sum = static_cast<float>(1.0 / level.lossmult_sum);
  // Without multiscale the kernel never reads lossmult; a null buffer is a valid argument then.
  const ::cl::Buffer no_buffer;
  const ::cl::Buffer& lossmult_buffer = lossmult ? lossmult->buffer() : no_buffer;
  ocl::set_args(*fwd_bwd_, where, comp_rgb, target_rgb, lossmult_buffer, level.level_weight, inv_lossmult_sum,
                d_comp_rgb, partials, as_uint(chunk.first_group, "first_group"),
                as_uint(chunk.batch_offset, "batch_offset"), as_uint(n, "n_rays"));
  ocl::launch_1d(*ctx_, *fwd_bwd_, n, where, group_size_);
}

void Loss::reduce(const ocl::DeviceArray<float>& partials, size_t n_groups, ocl::DeviceArray<float>& sums,
                  size_t out_slot) {
  const std::string where = "loss_reduce";
  partials.require_size(kSumsPerGroup * n_groups, where);
  sums.require_size(kSumsPerGroup * (out_slot + 1), where);
  ocl::set_args(*reduce_, where, partials, as_uint(n_groups, "n_groups"), sums, as_uint(out_slot, "out_slot"));
  ocl::launch_1d(*ctx_, *reduce_, 1, where);
}

}  // namespace mipnerf::ops
