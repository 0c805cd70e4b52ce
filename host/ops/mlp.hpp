// Host wrapper of kernels/mlp.cl: the MLP's bias/activation forward and the fused activation backward with
// per-block column sums. Each kernel's arguments are set here, once (the MLP, tests and benchmarks share it).
#pragma once

#include <cstddef>

#include "cl/buffer.hpp"
#include "cl/context.hpp"

namespace mipnerf::ops {

class MlpKernels {
 public:
  explicit MlpKernels(ocl::Context& ctx);

  // Rows per block of the column sums when they only feed a bias gradient.
  static constexpr size_t kRowsPerBlock = 64;
  static size_t blocks_for(size_t rows, size_t rows_per_block) { return (rows + rows_per_block - 1) / rows_per_block; }

  // mlp_bias_act_fwd: z [rows][cols] (view, written) += params[bias_offset + c]; then ReLU when relu.
  void bias_act_fwd(const ocl::MatrixView& z, size_t rows, size_t cols, const ocl::DeviceArray<float>& params,
                    size_t bias_offset, bool relu);

  // mlp_bias_ray_relu_fwd: z [rows][cols] = ReLU(z + ray_term[r / samples_per_ray] + bias); ray_term is
  // [rows / samples_per_ray][cols], dense.
  void bias_ray_relu_fwd(const ocl::MatrixView& z, size_t rows, size_t cols, const ocl::DeviceArray<float>& params,
                         size_t bias_offset, const ocl::DeviceArray<float>& ray_term, size_t samples_per_ray);

  // mlp_act_bwd_partial: when act is given, dz [rows][cols] (written) is masked by act > 0 (the layer's ReLU
  // output); without act, dz is only read. partials [blocks][cols] (dense) receive the column sums of each
  // block of rows_per_block rows.
  void act_bwd_partial(const ocl::MatrixView& dz, const ocl::MatrixView* act, size_t rows, size_t cols,
                       size_t rows_per_block, ocl::DeviceArray<float>& partials);

  // mlp_sum_partials: grad[grad_offset + c] += Σ_b partials[b][c] over n_blocks blocks.
  void sum_partials(const ocl::DeviceArray<float>& partials, size_t n_blocks, size_t cols,
                    ocl::DeviceArray<float>& grad, size_t grad_offset);

 private:
  ocl::Context* ctx_;
  ::cl::Kernel* bias_act_fwd_;
  ::cl::Kernel* bias_ray_relu_fwd_;
  ::cl::Kernel* act_bwd_partial_;
  ::cl::Kernel* sum_partials_;
};

}  // namespace mipnerf::ops
