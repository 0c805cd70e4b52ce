// Host wrapper of kernels/zip_features.cl.
#include "ops/zip_features.hpp"

#include "cl/launch.hpp"
#include "core/error.hpp"
#include "ops/stage_checks.hpp"

namespace mipnerf::ops {

ocl::BuildOptions zip_features_build_options(const ZipFeatureOptions& options) {
  return ocl::BuildOptions()
      .define("GRID_FEATURES", options.features)
      .define("GRID_DOWNWEIGHT", options.downweight ? 1 : 0)
      .define("GRID_APPEND_SCALE", options.append_scale ? 1 : 0)
      .define("ZIP_MULTISAMPLE", options.multisample ? 1 : 0)
      .define("ZIP_CYLINDER", options.cylinder ? 1 : 0)
      .define("ZIP_RANDOMIZED", options.randomized ? 1 : 0)
      .define("ZIP_CONTRACT", options.contract ? 1 : 0);
}

ZipFeatures::ZipFeatures(ocl::Context& ctx, const ZipFeatureOptions& options) : ctx_(&ctx), options_(options) {
  if (options_.features < 1 || options_.features > 16) {
    throw Error("zip features: " + std::to_string(options_.features) + " features per level (1 to 16)");
  }
  if (!(options_.box_size > 0.0f)) throw Error("zip features: the grid's cube needs a positive size");
  if (options_.contract && options_.cylinder) {
    throw Error("zip features: contraction is for world rays (cones); NDC's cylinders are bounded already");
  }
  // contract.cl only when contracting: it turns floating-point contraction off for what follows it.
  std::vector<std::string> sources = {"common.cl", "grid_encoding.cl", "multisample.cl"};
  if (options_.contract) sources.push_back("contract.cl");
  sources.push_back("zip_features.cl");
  auto& program = ctx.program(sources, zip_features_build_options(options_));
  fwd_ = &program.kernel("zip_features_fwd");
  bwd_ = &program.kernel("zip_features_bwd");
  bwd_by_level_ = &program.kernel("zip_features_bwd_by_level");
  level_scale_ = &program.kernel("zip_level_scale");
  weight_decay_ = &program.kernel("grid_weight_decay");
}

void ZipFeatures::check(const ZipFeatureInputs& in, const ZipGrid& grid, const std::string& where) const {
  detail::require(in.rays.origins, 3 * in.n_rays, where);
  detail::require(in.rays.directions, 3 * in.n_rays, where);
  detail::require(in.rays.radii, in.n_rays, where);
  detail::require(in.t_edges, in.n_rays * (in.n_intervals + 1), where);
  detail::require(grid.levels, 4 * grid.layout.size(), where);
  if (grid.layout.empty()) throw Error(where + ": a grid without levels");
  detail::to_uint(in.n_rays * in.n_intervals, where, "samples");
}

namespace {
cl_float4 box_of(const ZipFeatureOptions& o) { return {{o.box_min[0], o.box_min[1], o.box_min[2], o.box_size}}; }
}  // namespace

void ZipFeatures::level_scale(const ZipGrid& grid, const ocl::DeviceArray<float>& table,
                              ocl::DeviceArray<float>& level_scale) {
  const std::string where = "zip_level_scale";
  detail::require(table, grid_table_entries(grid.layout) * options_.features, where);
  detail::require(level_scale, grid.layout.size(), where);
  ocl::set_args(*level_scale_, where, grid.levels, table, level_scale, static_cast<cl_uint>(grid.layout.size()),
                options_.maxval());
  ocl::launch_1d(*ctx_, *level_scale_, grid.layout.size(), where);
}

void ZipFeatures::fwd(const ZipFeatureInputs& in, const ZipGrid& grid, const ocl::DeviceArray<float>& table,
                      const ocl::DeviceArray<float>& level_scale, ocl::DeviceArray<float>& features, RngKey key) {
  const std::string where = "zip_features_fwd";
  check(in, grid, where);
  const size_t samples = in.n_rays * in.n_intervals;
  detail::require(table, grid_table_entries(grid.layout) * options_.features, where);
  detail::require(level_scale, grid.layout.size(), where);
  detail::require(features, samples * grid.layout.size() * options_.level_width(), where);
  ocl::set_args(*fwd_, where, in.rays.origins, in.rays.directions, in.rays.radii, in.t_edges, grid.levels, table,
                level_scale, features, static_cast<cl_uint>(samples), static_cast<cl_uint>(in.n_intervals),
                static_cast<cl_uint>(grid.layout.size()), box_of(options_), options_.scale_mult,
                options_.precondition, static_cast<cl_ulong>(key.seed), static_cast<cl_uint>(key.step),
                static_cast<cl_uint>(key.first_ray));
  ocl::launch_1d(*ctx_, *fwd_, samples, where);
}

void ZipFeatures::bwd(const ZipFeatureInputs& in, const ZipGrid& grid, const ocl::DeviceArray<float>& d_features,
                      ocl::DeviceArray<float>& d_table, RngKey key) {
  const std::string where = "zip_features_bwd";
  check(in, grid, where);
  const size_t samples = in.n_rays * in.n_intervals;
  detail::require(d_table, grid_table_entries(grid.layout) * options_.features, where);
  detail::require(d_features, samples * grid.layout.size() * options_.level_width(), where);
  const bool by_level = options_.scatter == ZipFeatureOptions::Scatter::by_level;
  ::cl::Kernel& kernel = by_level ? *bwd_by_level_ : *bwd_;
  ocl::set_args(kernel, where, in.rays.origins, in.rays.directions, in.rays.radii, in.t_edges, grid.levels, d_features,
                d_table, static_cast<cl_uint>(samples), static_cast<cl_uint>(in.n_intervals),
                static_cast<cl_uint>(grid.layout.size()), box_of(options_), options_.scale_mult,
                options_.precondition, static_cast<cl_ulong>(key.seed), static_cast<cl_uint>(key.step),
                static_cast<cl_uint>(key.first_ray));
  // One work-item per work-group by level, so a CPU device runs the levels on all its cores.
  ocl::launch_1d(*ctx_, kernel, by_level ? grid.layout.size() : samples, where, by_level ? 1 : 0);
}

void ZipFeatures::weight_decay(const ZipGrid& grid, const ocl::DeviceArray<float>& table,
                               ocl::DeviceArray<float>& d_table, float mult) {
  const std::string where = "grid_weight_decay";
  const size_t values = grid_table_entries(grid.layout) * options_.features;
  detail::require(table, values, where);
  detail::require(d_table, values, where);
  detail::to_uint(values, where, "table values");
  ocl::set_args(*weight_decay_, where, grid.levels, table, d_table, static_cast<cl_uint>(grid.layout.size()), mult);
  ocl::launch_1d(*ctx_, *weight_decay_, values, where);
}

}  // namespace mipnerf::ops
