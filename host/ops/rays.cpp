// Host wrapper of kernels/rays.cl.
#include "ops/rays.hpp"

#include "cl/launch.hpp"
#include "core/camera.hpp"
#include "ops/stage_checks.hpp"

namespace mipnerf::ops {

ocl::BuildOptions rays_build_options(const RaysOptions& options) {
  ocl::BuildOptions build;
  if (options.ray_shape == RayShape::cylinder && options.ndc_scale_x > 0.0f && options.ndc_scale_y > 0.0f) {
    build.define_float("NDC_SCALE_X", options.ndc_scale_x).define_float("NDC_SCALE_Y", options.ndc_scale_y);
  }
  return build
      .define("RAY_SHAPE", static_cast<int>(options.ray_shape))
      .define_float("PIXEL_CENTER_OFFSET", options.pixel_center_offset)
      .define("SUBPIXEL_JITTER", options.jitter_subpixel ? 1 : 0)
      .define("VIEW_DEPENDENCE", options.view_dependence ? 1 : 0)
      .define("UNIT_VIEWDIRS", options.unit_viewdirs ? 1 : 0)
      .define("LENS_TABLES", options.lens_tables ? 1 : 0)
      .define_float("NDC_NEAR_PLANE", options.ndc_near_plane);
}

Rays::Rays(ocl::Context& ctx, const RaysOptions& options)
    : ctx_(&ctx), options_(options), no_lens_tables_(ctx, 4, "rays: no lens tables") {
  fwd_ = &ctx.program({"common.cl", "rays.cl"}, rays_build_options(options_)).kernel("rays_fwd");
}

void Rays::fwd(const RaysInputs& in, RayBundle& out, const RngKey& key) {
  const std::string where = "rays_fwd";
  const size_t stride = camera_layout::stride;
  if (in.cameras.size() % stride != 0) {
    throw Error(where + ": cameras buffer '" + in.cameras.name() + "' holds " + std::to_string(in.cameras.size()) +
                " floats, not a multiple of " + std::to_string(stride) + " (pack them with pack_cameras)");
  }
  const size_t n = in.n_rays;
  detail::require(in.camera_ids, n, where);
  detail::require(in.pixel_ids, n, where);
  detail::require(out.origins, 3 * n, where);
  detail::require(out.directions, 3 * n, where);
  if (options_.view_dependence) detail::require(out.viewdirs, 3 * n, where);
  detail::require(out.radii, n, where);
  detail::require(out.near, n, where);
  detail::require(out.far, n, where);
  detail::require(out.lossmult, n, where);
  if (in.lens_tables && !options_.lens_tables) {
    throw Error(where + ": lens tables given to a ray stage built without LENS_TABLES (RaysOptions::lens_tables)");
  }
  if (options_.lens_tables && (!in.lens_tables || in.lens_tables->size() % 4 != 0)) {
    throw Error(where + ": a ray stage built with LENS_TABLES needs the cameras' lens tables ([pixels][4] floats)");
  }
  const ocl::DeviceArray<float>& lens_tables = in.lens_tables ? *in.lens_tables : no_lens_tables_;
  ocl::set_args(*fwd_, where, in.cameras, in.camera_ids, in.pixel_ids, lens_tables, out.origins, out.directions, out.viewdirs,
                out.radii, out.near, out.far, out.lossmult, detail::to_uint(n, where, "rays"),
                detail::to_uint(in.cameras.size() / stride, where, "cameras"), static_cast<cl_ulong>(key.seed),
                static_cast<cl_uint>(key.step), static_cast<cl_uint>(key.first_ray));
  ocl::launch_1d(*ctx_, *fwd_, n, where);
}

}  // namespace mipnerf::ops
