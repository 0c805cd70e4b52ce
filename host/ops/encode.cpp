// Host wrapper of kernels/encode.cl.
#include "ops/encode.hpp"

#include <cstdlib>

#include "cl/launch.hpp"
#include "ops/stage_checks.hpp"

namespace mipnerf::ops {
namespace {

void check_degrees(const EncodingOptions& options, const std::string& where, bool allow_empty) {
  if (options.min_deg < 0 || options.max_deg > 60 || options.max_deg < options.min_deg ||
      (!allow_empty && options.max_deg == options.min_deg)) {
    throw Error(where + ": degrees [" + std::to_string(options.min_deg) + ", " + std::to_string(options.max_deg) +
                ") are not a valid range (0 ≤ min_deg " + (allow_empty ? "≤" : "<") + " max_deg ≤ 60)");
  }
}

bool choose_fused_per_row(const ocl::Context& ctx, const EncodeTuning& tuning) {
  switch (tuning.fused_items) {
    case EncodeTuning::FusedItems::per_row:
      return true;
    case EncodeTuning::FusedItems::per_row_and_degree:
      return false;
    default:
      return (ctx.device_info().type & CL_DEVICE_TYPE_CPU) != 0;
  }
}

// A sincos every K degrees (IPE_SINCOS_EVERY; its error bound in encode.cl): K = 4 on CPUs, where the sincos of
// every degree was ~70 % of the fused kernel (bench/results/kernel_runtimes.md measures K = 1 and 4 on PoCL and
// Intel's runtime); 1 elsewhere, where nothing has measured it. Only per-row items can double.
int choose_sincos_every(const ocl::Context& ctx, const EncodeTuning& tuning, bool per_row) {
  if (!per_row) return 1;
  if (tuning.sincos_every > 0) return tuning.sincos_every;
  if (const char* forced = std::getenv("MIPNERF_IPE_SINCOS_EVERY")) {
    const int k = std::atoi(forced);
    if (k < 1 || k > 8) {
      throw Error(std::string("MIPNERF_IPE_SINCOS_EVERY='") + forced + "' is not 1 to 8 (degrees per sincos)");
    }
    return k;
  }
  return (ctx.device_info().type & CL_DEVICE_TYPE_CPU) != 0 ? 4 : 1;
}

}  // namespace

Encode::Encode(ocl::Context& ctx, const GaussianOptions& options, const EncodeTuning& tuning)
    : ctx_(&ctx),
      gaussian_options_(options),
      fused_per_row_(choose_fused_per_row(ctx, tuning)),
      sincos_every_(choose_sincos_every(ctx, tuning, fused_per_row_)) {
  if (sincos_every_ < 1 || sincos_every_ > 8) {
    throw Error("Encode: sincos_every = " + std::to_string(sincos_every_) + " is not 1 to 8 (degrees per sincos)");
  }
  auto build_options = gaussian_build_options(options)
                           .define("GAUSSIAN_IPE_PER_ROW", fused_per_row_ ? 1 : 0)
                           .define("IPE_SINCOS_EVERY", sincos_every_);
  if (tuning.concat_pe) build_options.define("MIPNERF_CONCAT_PE", 1);
  auto& program = ctx.program({"common.cl", "gaussian.cl", "encode.cl"}, build_options);
  ipe_ = &program.kernel("ipe_fwd");
  pe_ = &program.kernel("pe_fwd");
  gaussian_ipe_ = &program.kernel("gaussian_ipe_fwd");
  if (tuning.concat_pe) gaussian_concat_pe_ = &program.kernel("gaussian_concat_pe_fwd");
}

void Encode::ipe(const EncodingOptions& options, const IpeInputs& in, ocl::DeviceArray<float>& features) {
  const std::string where = "ipe_fwd";
  check_degrees(options, where, false);
  detail::require(in.means, 3 * in.n_rows, where);
  detail::require(in.covs, 3 * in.n_rows, where);
  detail::require(features, in.n_rows * options.ipe_width(), where);
  const size_t items = in.n_rows * options.degrees();
  ocl::set_args(*ipe_, where, in.means, in.covs, features, detail::to_uint(in.n_rows, where, "rows"),
                static_cast<cl_int>(options.min_deg), static_cast<cl_int>(options.max_deg));
  detail::to_uint(items, where, "items");
  ocl::launch_1d(*ctx_, *ipe_, items, where);
}

void Encode::pe(const EncodingOptions& options, const PeInputs& in, ocl::DeviceArray<float>& features) {
  const std::string where = "pe_fwd";
  check_degrees(options, where, options.append_identity);
  detail::require(in.x, 3 * in.n_rows, where);
  detail::require(features, in.n_rows * options.pe_width(), where);
  const size_t items = in.n_rows * std::max(1, options.degrees());
  ocl::set_args(*pe_, where, in.x, features, detail::to_uint(in.n_rows, where, "rows"),
                static_cast<cl_int>(options.min_deg), static_cast<cl_int>(options.max_deg),
                static_cast<cl_uint>(options.append_identity ? 1 : 0));
  detail::to_uint(items, where, "items");
  ocl::launch_1d(*ctx_, *pe_, items, where);
}

void Encode::gaussian_ipe(const EncodingOptions& options, const GaussianInputs& in, ocl::DeviceArray<float>& features) {
  const std::string where = "gaussian_ipe_fwd";
  check_degrees(options, where, false);
  detail::require(in.rays.origins, 3 * in.n_rays, where);
  detail::require(in.rays.directions, 3 * in.n_rays, where);
  detail::require(in.rays.radii, in.n_rays, where);
  detail::require(in.t_edges, in.n_rays * (in.n_samples + 1), where);
  const size_t rows = in.n_rays * in.n_samples;
  detail::require(features, rows * options.ipe_width(), where);
  const size_t items = fused_per_row_ ? rows : rows * options.degrees();
  detail::to_uint(items, where, "items");
  ocl::set_args(*gaussian_ipe_, where, in.rays.origins, in.rays.directions, in.rays.radii, in.t_edges, features,
                detail::to_uint(in.n_rays, where, "rays"), detail::to_uint(in.n_samples, where, "samples"),
                static_cast<cl_int>(options.min_deg), static_cast<cl_int>(options.max_deg));
  ocl::launch_1d(*ctx_, *gaussian_ipe_, items, where);
}

void Encode::gaussian_concat_pe(const EncodingOptions& options, const GaussianInputs& in,
                                ocl::DeviceArray<float>& features) {
  const std::string where = "gaussian_concat_pe_fwd";
  if (gaussian_concat_pe_ == nullptr) {
    throw Error(where + ": this Encode was built without the concatenated-PE kernel (EncodeTuning::concat_pe)");
  }
  check_degrees(options, where, options.append_identity);
  if (options.covariance_degrees < 1 || options.covariance_degrees > 60) {
    throw Error(where + ": covariance_degrees = " + std::to_string(options.covariance_degrees) +
                " is not in 1..60 (the concatenated PE encodes the covariance with at least one degree)");
  }
  detail::require(in.rays.origins, 3 * in.n_rays, where);
  detail::require(in.rays.directions, 3 * in.n_rays, where);
  detail::require(in.rays.radii, in.n_rays, where);
  detail::require(in.t_edges, in.n_rays * (in.n_samples + 1), where);
  const size_t rows = in.n_rays * in.n_samples;
  detail::require(features, rows * options.concat_pe_width(), where);
  detail::to_uint(rows, where, "items");
  ocl::set_args(*gaussian_concat_pe_, where, in.rays.origins, in.rays.directions, in.rays.radii, in.t_edges, features,
                detail::to_uint(in.n_rays, where, "rays"), detail::to_uint(in.n_samples, where, "samples"),
                static_cast<cl_int>(options.min_deg), static_cast<cl_int>(options.max_deg),
                static_cast<cl_uint>(options.append_identity ? 1 : 0), static_cast<cl_int>(options.covariance_degrees));
  ocl::launch_1d(*ctx_, *gaussian_concat_pe_, rows, where);
}

}  // namespace mipnerf::ops
