// The kernel benchmark's kernels in the CPU reference: one case per kernel of the stage list (host/ops/stage_list).
#include "kernel_reference.hpp"

#include <functional>
#include <string>

#include "core/error.hpp"
#include "ref/activations.hpp"
#include "ref/encode.hpp"
#include "ref/gaussian.hpp"
#include "ref/rays.hpp"
#include "ref/render.hpp"
#include "ref/resample.hpp"
#include "ref/sample.hpp"

namespace mipnerf::bench {
namespace {

using Options = ops::RayMathOptions;
using Inputs = KernelBenchInputs;

// The reference's call of one listed kernel; a missing case is a compile error (-Werror=switch).
std::function<void()> reference_call(ops::KernelId id, const Options& o, Inputs& r, size_t R, size_t N,
                                     const RngKey& key) {
  using K = ops::KernelId;
  switch (id) {
    case K::rays_fwd:
      return [&o, &r, R, key] {
        ref::rays_fwd(o.rays, r.cameras, r.camera_ids, r.pixel_ids, r.o1, r.o2, r.o3, r.o4, r.o5, r.o6, r.o7, R, 1,
                      key);
      };
    case K::sample_stratified_fwd:
      return [&o, &r, R, N, key] { ref::sample_stratified_fwd(o.sample, r.near, r.far, r.o1, R, N, key); };
    case K::gaussian_fwd:
      return [&o, &r, R, N] {
        ref::gaussian_fwd(o.gaussian, r.origins, r.directions, r.radii, r.t_edges, r.o1, r.o2, R, N);
      };
    case K::ipe_fwd:
      return [&o, &r, R, N] { ref::ipe_fwd(o.ipe, r.means, r.covs, r.o1, R * N); };
    case K::gaussian_ipe_fwd:
      return [&o, &r, R, N] {
        ref::gaussian_ipe_fwd(o.gaussian, o.ipe, r.origins, r.directions, r.radii, r.t_edges, r.o1, R, N);
      };
    case K::pe_fwd:
      return [&o, &r, R] { ref::pe_fwd(o.view, r.viewdirs, r.o1, R); };
    case K::activations_fwd:
      return [&o, &r, R, N] { ref::activations_fwd(o.activation, r.raw_density, r.raw_rgb, r.o1, r.o2, R * N); };
    case K::activations_bwd:
      return [&o, &r, R, N] {
        ref::activations_bwd(o.activation, r.raw_density, r.raw_rgb, r.density, r.rgb, r.o1, r.o2, R * N);
      };
    case K::render_fwd:
      return [&o, &r, R, N] {
        ref::render_fwd(o.render, r.rgb, r.density, r.t_edges, r.directions, r.o1, r.o2, r.o3, r.o4, R, N);
      };
    case K::render_bwd:
      return [&o, &r, R, N] {
        ref::render_bwd(o.render, r.rgb, r.density, r.t_edges, r.directions, r.weights, r.d_comp, nullptr, r.o1, r.o2,
                        R, N);
      };
    case K::render_raw_fwd:
      return [&o, &r, R, N] {
        ref::render_raw_fwd(o.render, o.activation, r.raw_rgb, r.raw_density, r.t_edges, r.directions, r.o1, r.o2, r.o3,
                            r.o4, R, N);
      };
    case K::render_raw_bwd:
      return [&o, &r, R, N] {
        ref::render_raw_bwd(o.render, o.activation, r.raw_rgb, r.raw_density, r.t_edges, r.directions, r.weights,
                            r.d_comp, nullptr, r.o1, r.o2, R, N);
      };
    case K::resample_fwd:
      return [&o, &r, R, N, key] { ref::resample_fwd(o.resample, r.t_edges, r.weights, r.o1, R, N, N, key); };
  }
  throw Error("kernel benchmark: kernel id " + std::to_string(static_cast<int>(id)) + " is not in the stage list");
}

}  // namespace

ReferenceStages reference_stages() { return reference_call; }

}  // namespace mipnerf::bench
