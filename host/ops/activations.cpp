// Host wrapper of kernels/activations.cl.
#include "ops/activations.hpp"

#include "cl/launch.hpp"
#include "ops/stage_checks.hpp"
#include "ops/vector_items.hpp"

namespace mipnerf::ops {

ocl::BuildOptions activation_build_options(const ActivationOptions& options) {
  return ocl::BuildOptions()
      .define("DENSITY_ACTIVATION", static_cast<int>(options.density))
      .define_float("DENSITY_BIAS", options.density_bias)
      .define_float("RGB_PADDING", options.rgb_padding);
}

namespace {

// Other CPU runtimes per row, GPUs per value (ActivationItems).
ActivationItems items_without_vectors(const ocl::Context& ctx) {
  const bool cpu = (ctx.device_info().type & CL_DEVICE_TYPE_CPU) != 0;
  return cpu ? ActivationItems::per_row : ActivationItems::per_value;
}

// ACTIVATION_ITEMS of activations.cl.
int items_define(ActivationItems items) {
  switch (items) {
    case ActivationItems::per_row:
      return 1;
    case ActivationItems::per_vector:
      return 2;
    default:
      return 0;
  }
}

}  // namespace

// Per value or per vector (activations.cl): the colour items' work-groups first, then the densities' from the next
// group on, so no group holds both (the kernel tells them apart by group id, from the local size given here).
void Activations::launch(::cl::Kernel& kernel, size_t n_rows, const std::string& where) {
  if (items_ == ActivationItems::per_row) return ocl::launch_1d(*ctx_, kernel, n_rows, where);
  const size_t per_item = items_ == ActivationItems::per_vector ? kVectorWidth : 1;
  const auto items_for = [&](size_t values) { return (values + per_item - 1) / per_item; };
  const size_t local = ctx_->traits().local_size_1d;
  const size_t n_items = ocl::round_up(items_for(3 * n_rows), local) + items_for(n_rows);
  detail::to_uint(ocl::round_up(n_items, local), where, "work-items");  // the kernels index them in 32 bits
  detail::to_uint(3 * n_rows, where, "colour values");
  ocl::launch_1d(*ctx_, kernel, n_items, where, local);
}

Activations::Activations(ocl::Context& ctx, const ActivationOptions& options, ActivationItems items)
    : ctx_(&ctx),
      options_(options),
      items_(items_for_device(ctx, items, ActivationItems::per_vector, items_without_vectors(ctx))) {
  auto& program = ctx.program({"common.cl", "activations.cl"},
                              activation_build_options(options_).define("ACTIVATION_ITEMS", items_define(items_)));
  fwd_ = &program.kernel("activations_fwd");
  bwd_ = &program.kernel("activations_bwd");
}

void Activations::fwd(const ActivationInputs& in, const ActivationOutputs& out) {
  const std::string where = "activations_fwd";
  detail::require(in.raw_density, in.n_rows, where);
  detail::require(in.raw_rgb, 3 * in.n_rows, where);
  detail::require(out.density, in.n_rows, where);
  detail::require(out.rgb, 3 * in.n_rows, where);
  ocl::set_args(*fwd_, where, in.raw_density, in.raw_rgb, out.density, out.rgb,
                detail::to_uint(in.n_rows, where, "rows"));
  launch(*fwd_, in.n_rows, where);
}

void Activations::bwd(const ActivationInputs& in, const ActivationGradients& grads, const ActivationRawGradients& out) {
  const std::string where = "activations_bwd";
  detail::require(in.raw_density, in.n_rows, where);
  detail::require(in.raw_rgb, 3 * in.n_rows, where);
  detail::require(grads.d_density, in.n_rows, where);
  detail::require(grads.d_rgb, 3 * in.n_rows, where);
  detail::require(out.d_raw_density, in.n_rows, where);
  detail::require(out.d_raw_rgb, 3 * in.n_rows, where);
  ocl::set_args(*bwd_, where, in.raw_density, in.raw_rgb, grads.d_density, grads.d_rgb, out.d_raw_density,
                out.d_raw_rgb, detail::to_uint(in.n_rows, where, "rows"));
  launch(*bwd_, in.n_rows, where);
}

}  // namespace mipnerf::ops
