// Host wrapper of kernels/sample.cl.
#include "ops/sample.hpp"

#include "cl/launch.hpp"
#include "ops/stage_checks.hpp"
#include "ops/vector_items.hpp"

namespace mipnerf::ops {

ocl::BuildOptions sample_build_options(const SampleOptions& options) {
  return ocl::BuildOptions().define("SAMPLE_LINDISP", options.lindisp ? 1 : 0);
}

Sample::Sample(ocl::Context& ctx, const SampleOptions& options, SampleItems items)
    : ctx_(&ctx),
      options_(options),
      items_(items_for_device(ctx, items, SampleItems::per_vector, SampleItems::per_group)) {
  auto& program = ctx.program(
      {"common.cl", "sample.cl"},
      sample_build_options(options_).define("SAMPLE_GROUPS_PER_VECTOR", items_ == SampleItems::per_vector ? 1 : 0));
  stratified_ = &program.kernel("sample_stratified_fwd");
  merge_ = &program.kernel("sample_merge_fwd");
}

void Sample::stratified(const StratifiedInputs& in, ocl::DeviceArray<float>& t_edges, const RngKey& key) {
  const std::string where = "sample_stratified_fwd";
  if (in.n_samples == 0) throw Error(where + ": n_samples must be at least 1");
  detail::require(in.rays.near, in.n_rays, where);
  detail::require(in.rays.far, in.n_rays, where);
  detail::require(t_edges, in.n_rays * (in.n_samples + 1), where);
  ocl::set_args(*stratified_, where, in.rays.near, in.rays.far, t_edges, detail::to_uint(in.n_rays, where, "rays"),
                detail::to_uint(in.n_samples, where, "samples"), static_cast<cl_uint>(options_.randomized ? 1 : 0),
                static_cast<cl_ulong>(key.seed), static_cast<cl_uint>(key.step), static_cast<cl_uint>(key.first_ray));
  const size_t groups = (in.n_samples + 1 + 3) / 4;  // of 4 edges, per ray
  const size_t items_per_ray = items_ == SampleItems::per_vector ? (groups + kVectorWidth - 1) / kVectorWidth : groups;
  ocl::launch_1d(*ctx_, *stratified_, in.n_rays * items_per_ray, where);
}

void Sample::merge(const MergeInputs& in, ocl::DeviceArray<float>& t_out) {
  const std::string where = "sample_merge_fwd";
  detail::require(in.t_a, in.n_rays * in.len_a, where);
  detail::require(in.t_b, in.n_rays * in.len_b, where);
  detail::require(t_out, in.n_rays * (in.len_a + in.len_b), where);
  ocl::set_args(*merge_, where, in.t_a, in.t_b, t_out, detail::to_uint(in.n_rays, where, "rays"),
                detail::to_uint(in.len_a, where, "len_a"), detail::to_uint(in.len_b, where, "len_b"));
  ocl::launch_1d(*ctx_, *merge_, in.n_rays, where);
}

}  // namespace mipnerf::ops
