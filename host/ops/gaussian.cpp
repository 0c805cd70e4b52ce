// Host wrapper of kernels/gaussian.cl.
#include "ops/gaussian.hpp"

#include "cl/launch.hpp"
#include "ops/stage_checks.hpp"
#include "ops/vector_items.hpp"

namespace mipnerf::ops {

ocl::BuildOptions gaussian_build_options(const GaussianOptions& options) {
  return ocl::BuildOptions().define("RAY_SHAPE", static_cast<int>(options.ray_shape));
}

Gaussian::Gaussian(ocl::Context& ctx, const GaussianOptions& options, GaussianItems items)
    : ctx_(&ctx),
      options_(options),
      items_(items_for_device(ctx, items, GaussianItems::per_vector, GaussianItems::per_row)) {
  auto& program = ctx.program({"common.cl", "gaussian.cl"},
                              gaussian_build_options(options_).define("GAUSSIAN_SAMPLES_PER_VECTOR",
                                                                      items_ == GaussianItems::per_vector ? 1 : 0));
  fwd_ = &program.kernel("gaussian_fwd");
  points_ = &program.kernel("gaussian_points_fwd");
}

void Gaussian::check(const GaussianInputs& in, const GaussianOutputs& out, const std::string& where, bool radii) const {
  detail::require(in.rays.origins, 3 * in.n_rays, where);
  detail::require(in.rays.directions, 3 * in.n_rays, where);
  if (radii) detail::require(in.rays.radii, in.n_rays, where);
  detail::require(in.t_edges, in.n_rays * (in.n_samples + 1), where);
  detail::require(out.means, 3 * in.n_rays * in.n_samples, where);
  detail::require(out.covs, 3 * in.n_rays * in.n_samples, where);
  detail::to_uint(in.n_rays * in.n_samples, where, "rows");
}

void Gaussian::fwd(const GaussianInputs& in, const GaussianOutputs& out) {
  const std::string where = "gaussian_fwd";
  check(in, out, where, true);
  ocl::set_args(*fwd_, where, in.rays.origins, in.rays.directions, in.rays.radii, in.t_edges, out.means, out.covs,
                detail::to_uint(in.n_rays, where, "rays"), detail::to_uint(in.n_samples, where, "samples"));
  const size_t items = items_ == GaussianItems::per_vector
                           ? in.n_rays * ((in.n_samples + kVectorWidth - 1) / kVectorWidth)
                           : in.n_rays * in.n_samples;
  ocl::launch_1d(*ctx_, *fwd_, items, where);
}

void Gaussian::points(const GaussianInputs& in, const GaussianOutputs& out) {
  const std::string where = "gaussian_points_fwd";
  check(in, out, where, false);
  ocl::set_args(*points_, where, in.rays.origins, in.rays.directions, in.t_edges, out.means, out.covs,
                detail::to_uint(in.n_rays, where, "rays"), detail::to_uint(in.n_samples, where, "samples"));
  ocl::launch_1d(*ctx_, *points_, in.n_rays * in.n_samples, where);
}

}  // namespace mipnerf::ops
