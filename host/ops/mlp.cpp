// Host wrapper of kernels/mlp.cl.
#include "ops/mlp.hpp"

#include <algorithm>
#include <string>

#include "core/error.hpp"
#include "cl/launch.hpp"
#include "ops/stage_checks.hpp"

namespace mipnerf::ops {
namespace {

// Elements a row-major rows×cols view with leading dimension ld spans from its offset.
size_t span(size_t rows, size_t cols, size_t ld) { return rows == 0 ? 0 : (rows - 1) * ld + cols; }

void require_view(const ocl::MatrixView& v, size_t rows, size_t cols, const std::string& where, const char* which) {
  if (v.array == nullptr) throw Error(where + ": " + which + " has no buffer");
  if (v.ld < cols) {
    throw Error(where + ": " + which + " has leading dimension " + std::to_string(v.ld) + " < its " +
                std::to_string(cols) + " columns");
  }
  v.array->require_size(v.offset + span(rows, cols, v.ld), where + " " + which);
}

// A 2-D work-group for a [rows][cols] sweep: x over columns (contiguous), as wide as the columns need up to
// the device's 1-D size, the rest over rows.
void local_2d(const ocl::Context& ctx, size_t cols, size_t& local_x, size_t& local_y) {
  const size_t group = ctx.traits().local_size_1d;
  local_x = 1;
  while (local_x < cols && local_x < group) local_x *= 2;
  local_y = std::max<size_t>(1, group / local_x);
}

}  // namespace

MlpKernels::MlpKernels(ocl::Context& ctx) : ctx_(&ctx) {
  auto& program = ctx.program({"common.cl", "mlp.cl"});
  bias_act_fwd_ = &program.kernel("mlp_bias_act_fwd");
  bias_ray_relu_fwd_ = &program.kernel("mlp_bias_ray_relu_fwd");
  act_bwd_partial_ = &program.kernel("mlp_act_bwd_partial");
  sum_partials_ = &program.kernel("mlp_sum_partials");
}

void MlpKernels::bias_act_fwd(const ocl::MatrixView& z, size_t rows, size_t cols,
                              const ocl::DeviceArray<float>& params, size_t bias_offset, bool relu) {
  const std::string where = "mlp_bias_act_fwd";
  if (rows == 0 || cols == 0) return;
  require_view(z, rows, cols, where, "z");
  params.require_size(bias_offset + cols, where);
  ocl::set_args(*bias_act_fwd_, where, *z.array, detail::to_uint(z.offset, where, "offset"),
                detail::to_uint(z.ld, where, "ld"), detail::to_uint(rows, where, "rows"),
                detail::to_uint(cols, where, "cols"), params, detail::to_uint(bias_offset, where, "bias_offset"),
                cl_uint{relu ? 1u : 0u});
  size_t lx = 0, ly = 0;
  local_2d(*ctx_, cols, lx, ly);
  ocl::launch_2d(*ctx_, *bias_act_fwd_, cols, rows, lx, ly, where);
}

void MlpKernels::bias_ray_relu_fwd(const ocl::MatrixView& z, size_t rows, size_t cols,
                                   const ocl::DeviceArray<float>& params, size_t bias_offset,
                                   const ocl::DeviceArray<float>& ray_term, size_t samples_per_ray) {
  const std::string where = "mlp_bias_ray_relu_fwd";
  if (rows == 0 || cols == 0) return;
  if (samples_per_ray == 0 || rows % samples_per_ray != 0) {
    throw Error(where + ": " + std::to_string(rows) + " rows are not a whole number of rays of " +
                std::to_string(samples_per_ray) + " samples");
  }
  require_view(z, rows, cols, where, "z");
  params.require_size(bias_offset + cols, where);
  ray_term.require_size(rows / samples_per_ray * cols, where);
  ocl::set_args(*bias_ray_relu_fwd_, where, *z.array, detail::to_uint(z.offset, where, "offset"),
                detail::to_uint(z.ld, where, "ld"), detail::to_uint(rows, where, "rows"),
                detail::to_uint(cols, where, "cols"), params, detail::to_uint(bias_offset, where, "bias_offset"),
                ray_term, detail::to_uint(samples_per_ray, where, "samples_per_ray"));
  size_t lx = 0, ly = 0;
  local_2d(*ctx_, cols, lx, ly);
  ocl::launch_2d(*ctx_, *bias_ray_relu_fwd_, cols, rows, lx, ly, where);
}

void MlpKernels::act_bwd_partial(const ocl::MatrixView& dz, const ocl::MatrixView* act, size_t rows, size_t cols,
                                 size_t rows_per_block, ocl::DeviceArray<float>& partials) {
  const std::string where = "mlp_act_bwd_partial";
  if (rows == 0 || cols == 0) return;
  if (rows_per_block == 0) throw Error(where + ": rows_per_block must be positive");
  require_view(dz, rows, cols, where, "dz");
  if (act) require_view(*act, rows, cols, where, "act");
  const size_t n_blocks = blocks_for(rows, rows_per_block);
  partials.require_size(n_blocks * cols, where);
  // Without an activation the kernel never reads `act`; dz stands in for it.
  const ocl::MatrixView& act_view = act ? *act : dz;
  ocl::set_args(*act_bwd_partial_, where, *dz.array, detail::to_uint(dz.offset, where, "dz offset"),
                detail::to_uint(dz.ld, where, "dz ld"), *act_view.array,
                detail::to_uint(act_view.offset, where, "act offset"), detail::to_uint(act_view.ld, where, "act ld"),
                detail::to_uint(rows, where, "rows"), detail::to_uint(cols, where, "cols"),
                detail::to_uint(rows_per_block, where, "rows_per_block"), cl_uint{act ? 1u : 0u}, partials);
  size_t lx = 0, ly = 0;
  local_2d(*ctx_, cols, lx, ly);
  ocl::launch_2d(*ctx_, *act_bwd_partial_, cols, n_blocks, lx, ly, where);
}

void MlpKernels::sum_partials(const ocl::DeviceArray<float>& partials, size_t n_blocks, size_t cols,
                              ocl::DeviceArray<float>& grad, size_t grad_offset) {
  const std::string where = "mlp_sum_partials";
  if (cols == 0) return;
  partials.require_size(n_blocks * cols, where);
  grad.require_size(grad_offset + cols, where);
  ocl::set_args(*sum_partials_, where, partials, detail::to_uint(n_blocks, where, "n_blocks"),
                detail::to_uint(cols, where, "cols"), grad, detail::to_uint(grad_offset, where, "grad_offset"));
  ocl::launch_1d(*ctx_, *sum_partials_, cols, where);
}

}  // namespace mipnerf::ops
