// Host wrapper of kernels/sample_intervals.cl.
#include "ops/sample_intervals.hpp"

#include <cmath>

#include "cl/launch.hpp"
#include "core/error.hpp"
#include "ops/stage_checks.hpp"

namespace mipnerf::ops {

SampleIntervals::SampleIntervals(ocl::Context& ctx, RayDistance ray_distance)
    : ctx_(&ctx), ray_distance_(ray_distance) {
  auto& program = ctx.program({"common.cl", "sample_intervals.cl"},
                              ocl::BuildOptions().define("RAY_DISTANCE", static_cast<int>(ray_distance)));
  fwd_ = &program.kernel("sample_intervals_fwd");
  s_to_t_ = &program.kernel("sample_intervals_s_to_t");
}

namespace {

// The options the kernel cannot check per ray; each message says which value and what the official allows.
void check_sample_intervals_options(const SampleIntervalsOptions& options, const std::string& where) {
  if (!std::isfinite(options.anneal) || options.anneal < 0.0f) {
    throw Error(where + ": anneal must be finite and ≥ 0 (proposal_anneal gives [0, 1]), got " +
                std::to_string(options.anneal));
  }
  if (!std::isfinite(options.resample_padding) || options.resample_padding < 0.0f) {
    throw Error(where + ": resample_padding must be finite and ≥ 0, got " + std::to_string(options.resample_padding));
  }
  if (std::isnan(options.domain_near) || std::isnan(options.domain_far) ||
      !(options.domain_near <= options.domain_far)) {
    throw Error(where + ": the domain must have domain_near ≤ domain_far (official (init_s_near, init_s_far)), got [" +
                std::to_string(options.domain_near) + ", " + std::to_string(options.domain_far) + "]");
  }
}

}  // namespace

void SampleIntervals::fwd(const SampleIntervalsOptions& options, const SampleIntervalsInputs& in,
                          ocl::DeviceArray<float>& s_new, const RngKey& key) {
  const std::string where = "sample_intervals_fwd";
  if (in.n_intervals == 0) throw Error(where + ": n_intervals must be at least 1 (the previous level's intervals)");
  if (in.new_intervals < 2) {
    throw Error(where +
                ": new_intervals must be at least 2 (the edges reflect the first and last midpoints; the "
                "official sample_intervals refuses num_samples <= 1), got " +
                std::to_string(in.new_intervals));
  }
  check_sample_intervals_options(options, where);
  detail::require(in.s_edges, in.n_rays * (in.n_intervals + 1), where);
  detail::require(in.weights, in.n_rays * in.n_intervals, where);
  detail::require(s_new, in.n_rays * (in.new_intervals + 1), where);
  ocl::set_args(*fwd_, where, in.s_edges, in.weights, s_new, detail::to_uint(in.n_rays, where, "rays"),
                detail::to_uint(in.n_intervals, where, "intervals"),
                detail::to_uint(in.new_intervals, where, "new intervals"), options.anneal, options.resample_padding,
                options.domain_near, options.domain_far, static_cast<cl_uint>(options.randomized ? 1 : 0),
                static_cast<cl_uint>(options.single_jitter ? 1 : 0), static_cast<cl_ulong>(key.seed),
                static_cast<cl_uint>(key.step), static_cast<cl_uint>(key.first_ray));
  ocl::launch_1d(*ctx_, *fwd_, in.n_rays, where);
}

void SampleIntervals::s_to_t(const ocl::DeviceArray<float>& s, const RayBundle& rays, size_t n_rays, size_t n_per_ray,
                             ocl::DeviceArray<float>& t) {
  const std::string where = "sample_intervals_s_to_t";
  if (n_per_ray == 0) throw Error(where + ": n_per_ray must be at least 1 (the edges of each ray)");
  detail::require(s, n_rays * n_per_ray, where);
  detail::require(t, n_rays * n_per_ray, where);
  detail::require(rays.near, n_rays, where);
  detail::require(rays.far, n_rays, where);
  ocl::set_args(*s_to_t_, where, s, rays.near, rays.far, t, detail::to_uint(n_rays, where, "rays"),
                detail::to_uint(n_per_ray, where, "values per ray"));
  ocl::launch_1d(*ctx_, *s_to_t_, n_rays * n_per_ray, where);
}

}  // namespace mipnerf::ops
