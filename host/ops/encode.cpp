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

EncodeTuning::FusedItems choose_fused_items(const ocl::Context& ctx, const EncodeTuning& tuning) {
  using Items = EncodeTuning::FusedItems;
  const auto& device = ctx.device_info();
  if (tuning.fused_items == Items::per_row_and_axis && !device.has_fp64) {
    throw Error("Encode: the per-(row, axis) Gaussian + IPE kernel needs fp64, which " + device.name + " lacks");
  }
  if (tuning.fused_items != Items::device_default) return tuning.fused_items;
  if ((device.type & CL_DEVICE_TYPE_CPU) == 0) return Items::per_row_and_degree;
  return device.has_fp64 ? Items::per_row_and_axis : Items::per_row;
}

// A sincos every K degrees (IPE_SINCOS_EVERY; its error bound in encode.cl): K = 4 on CPUs, where the sincos of
// every degree was ~70 % of the fused kernel (bench/results/kernel_runtimes/kernel_runtimes.md measures K = 1 and 4 on PoCL and
// Intel's runtime); 1 elsewhere, where nothing has measured it. Items per (row, degree) cannot double.
int choose_sincos_every(const ocl::Context& ctx, const EncodeTuning& tuning, EncodeTuning::FusedItems items) {
  if (items == EncodeTuning::FusedItems::per_row_and_degree) return 1;
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
      fused_items_(choose_fused_items(ctx, tuning)),
      sincos_every_(choose_sincos_every(ctx, tuning, fused_items_)) {
  if (sincos_every_ < 1 || sincos_every_ > 8) {
    throw Error("Encode: sincos_every = " + std::to_string(sincos_every_) + " is not 1 to 8 (degrees per sincos)");
  }
  auto build_options = gaussian_build_options(options)
                           .define("GAUSSIAN_IPE_PER_ROW", fused_items_ == EncodeTuning::FusedItems::per_row ? 1 : 0)
                           .define("IPE_SINCOS_EVERY", sincos_every_);
  if (tuning.concat_pe) build_options.define("MIPNERF_CONCAT_PE", 1);
  auto& program = ctx.program({"common.cl", "gaussian.cl", "encode.cl"}, build_options);
  ipe_ = &program.kernel("ipe_fwd");
  pe_ = &program.kernel("pe_fwd");
  gaussian_ipe_ = &program.kernel("gaussian_ipe_fwd");
  if (tuning.concat_pe) gaussian_concat_pe_ = &program.kernel("gaussian_concat_pe_fwd");
}

::cl::Kernel& Encode::axis_kernel(const EncodingOptions& options, const std::string& name, int sincos_every) {
  const AxisKernelKey key{name, options.min_deg, options.max_deg, sincos_every};
  auto found = axis_kernels_.find(key);
  if (found != axis_kernels_.end()) return *found->second;
  // Its own program: the degrees are compiled in, and denormals are flushed in it only (encode.cl says why).
  auto& program =
      ctx_->program({"common.cl", "gaussian.cl", "encode.cl"}, gaussian_build_options(gaussian_options_)
                                                                   .define("IPE_SINCOS_EVERY", sincos_every)
                                                                   .define("IPE_AXIS_MIN_DEG", options.min_deg)
                                                                   .define("IPE_AXIS_MAX_DEG", options.max_deg)
                                                                   .flag("-cl-denorms-are-zero"));
  ::cl::Kernel* kernel = &program.kernel(name);
  axis_kernels_.emplace(key, kernel);
  return *kernel;
}

void Encode::ipe(const EncodingOptions& options, const IpeInputs& in, ocl::DeviceArray<float>& features) {
  const std::string where = "ipe_fwd";
  check_degrees(options, where, false);
  detail::require(in.means, 3 * in.n_rows, where);
  detail::require(in.covs, 3 * in.n_rows, where);
  detail::require(features, in.n_rows * options.ipe_width(), where);
  const cl_uint n_rows = detail::to_uint(in.n_rows, where, "rows");
  if (fused_items_ == EncodeTuning::FusedItems::per_row_and_axis) {
    detail::to_uint(in.n_rows * options.ipe_width(), where, "features");  // the kernel indexes them in 32 bits
    auto& kernel = axis_kernel(options, "ipe_axis_fwd", 1);
    ocl::set_args(kernel, where, in.means, in.covs, features, n_rows);
    return ocl::launch_1d(*ctx_, kernel, 3 * in.n_rows, where);
  }
  const size_t items = in.n_rows * options.degrees();
  ocl::set_args(*ipe_, where, in.means, in.covs, features, n_rows, static_cast<cl_int>(options.min_deg),
                static_cast<cl_int>(options.max_deg));
  detail::to_uint(items, where, "items");
  ocl::launch_1d(*ctx_, *ipe_, items, where);
}

void Encode::pe(const EncodingOptions& options, const PeInputs& in, ocl::DeviceArray<float>& features) {
  const std::string where = "pe_fwd";
  check_degrees(options, where, options.append_identity);
  detail::require(in.x, 3 * in.n_rows, where);
  detail::require(features, in.n_rows * options.pe_width(), where);
  const cl_uint n_rows = detail::to_uint(in.n_rows, where, "rows");
  const cl_uint append_identity = options.append_identity ? 1 : 0;
  if (fused_items_ == EncodeTuning::FusedItems::per_row_and_axis) {
    detail::to_uint(in.n_rows * options.pe_width(), where, "features");  // the kernel indexes them in 32 bits
    auto& kernel = axis_kernel(options, "pe_axis_fwd", 1);
    ocl::set_args(kernel, where, in.x, features, n_rows, append_identity);
    return ocl::launch_1d(*ctx_, kernel, 3 * in.n_rows, where);
  }
  const size_t items = in.n_rows * std::max(1, options.degrees());
  ocl::set_args(*pe_, where, in.x, features, n_rows, static_cast<cl_int>(options.min_deg),
                static_cast<cl_int>(options.max_deg), append_identity);
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
  const cl_uint n_rays = detail::to_uint(in.n_rays, where, "rays"),
                n_samples = detail::to_uint(in.n_samples, where, "samples");
  if (fused_items_ == EncodeTuning::FusedItems::per_row_and_axis) {
    detail::to_uint(rows * options.ipe_width(), where, "features");  // the kernel indexes them in 32 bits
    auto& kernel = axis_kernel(options, "gaussian_ipe_axis_fwd", sincos_every_);
    ocl::set_args(kernel, where, in.rays.origins, in.rays.directions, in.rays.radii, in.t_edges, features, n_rays,
                  n_samples);
    return ocl::launch_1d(*ctx_, kernel, 3 * rows, where);
  }
  const size_t items = fused_items_ == EncodeTuning::FusedItems::per_row ? rows : rows * options.degrees();
  detail::to_uint(items, where, "items");
  ocl::set_args(*gaussian_ipe_, where, in.rays.origins, in.rays.directions, in.rays.radii, in.t_edges, features, n_rays,
                n_samples, static_cast<cl_int>(options.min_deg), static_cast<cl_int>(options.max_deg));
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
