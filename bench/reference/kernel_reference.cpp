// The kernel benchmark's kernels in the CPU reference: one entry per kernel of the stage list (host/ops/stage_list).
#include "kernel_reference.hpp"

#include <map>

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

using Call = std::function<void(const ops::RayMathOptions&, KernelBenchInputs&, size_t R, size_t N, const RngKey&)>;

const std::map<std::string, Call>& calls() {
  static const std::map<std::string, Call> table = {
      {"rays_fwd",
       [](const ops::RayMathOptions& o, KernelBenchInputs& r, size_t R, size_t, const RngKey& key) {
         ref::rays_fwd(o.rays, r.cameras, r.camera_ids, r.pixel_ids, r.o1, r.o2, r.o3, r.o4, r.o5, r.o6, r.o7, R, 1,
                       key);
       }},
      {"sample_stratified_fwd",
       [](const ops::RayMathOptions& o, KernelBenchInputs& r, size_t R, size_t N, const RngKey& key) {
         ref::sample_stratified_fwd(o.sample, r.near, r.far, r.o1, R, N, key);
       }},
      {"gaussian_fwd",
       [](const ops::RayMathOptions& o, KernelBenchInputs& r, size_t R, size_t N, const RngKey&) {
         ref::gaussian_fwd(o.gaussian, r.origins, r.directions, r.radii, r.t_edges, r.o1, r.o2, R, N);
       }},
      {"ipe_fwd",
       [](const ops::RayMathOptions& o, KernelBenchInputs& r, size_t R, size_t N, const RngKey&) {
         ref::ipe_fwd(o.ipe, r.means, r.covs, r.o1, R * N);
       }},
      {"gaussian_ipe_fwd",
       [](const ops::RayMathOptions& o, KernelBenchInputs& r, size_t R, size_t N, const RngKey&) {
         ref::gaussian_ipe_fwd(o.gaussian, o.ipe, r.origins, r.directions, r.radii, r.t_edges, r.o1, R, N);
       }},
      {"pe_fwd",
       [](const ops::RayMathOptions& o, KernelBenchInputs& r, size_t R, size_t, const RngKey&) {
         ref::pe_fwd(o.view, r.viewdirs, r.o1, R);
       }},
      {"activations_fwd",
       [](const ops::RayMathOptions& o, KernelBenchInputs& r, size_t R, size_t N, const RngKey&) {
         ref::activations_fwd(o.activation, r.raw_density, r.raw_rgb, r.o1, r.o2, R * N);
       }},
      {"activations_bwd",
       [](const ops::RayMathOptions& o, KernelBenchInputs& r, size_t R, size_t N, const RngKey&) {
         ref::activations_bwd(o.activation, r.raw_density, r.raw_rgb, r.density, r.rgb, r.o1, r.o2, R * N);
       }},
      {"render_fwd",
       [](const ops::RayMathOptions& o, KernelBenchInputs& r, size_t R, size_t N, const RngKey&) {
         ref::render_fwd(o.render, r.rgb, r.density, r.t_edges, r.directions, r.o1, r.o2, r.o3, r.o4, R, N);
       }},
      {"render_bwd",
       [](const ops::RayMathOptions& o, KernelBenchInputs& r, size_t R, size_t N, const RngKey&) {
         ref::render_bwd(o.render, r.rgb, r.density, r.t_edges, r.directions, r.weights, r.d_comp, nullptr, r.o1,
                         r.o2, R, N);
       }},
      {"render_raw_fwd",
       [](const ops::RayMathOptions& o, KernelBenchInputs& r, size_t R, size_t N, const RngKey&) {
         ref::render_raw_fwd(o.render, o.activation, r.raw_rgb, r.raw_density, r.t_edges, r.directions, r.o1, r.o2,
                             r.o3, r.o4, R, N);
       }},
      {"render_raw_bwd",
       [](const ops::RayMathOptions& o, KernelBenchInputs& r, size_t R, size_t N, const RngKey&) {
         ref::render_raw_bwd(o.render, o.activation, r.raw_rgb, r.raw_density, r.t_edges, r.directions, r.weights,
                             r.d_comp, nullptr, r.o1, r.o2, R, N);
       }},
      {"resample_fwd",
       [](const ops::RayMathOptions& o, KernelBenchInputs& r, size_t R, size_t N, const RngKey& key) {
         ref::resample_fwd(o.resample, r.t_edges, r.weights, r.o1, R, N, N, key);
       }},
  };
  return table;
}

}  // namespace

std::vector<std::string> reference_kernels() {
  std::vector<std::string> names;
  for (const auto& entry : calls()) names.push_back(entry.first);
  return names;
}

ReferenceStages reference_stages() {
  return [](const std::string& kernel, const ops::RayMathOptions& options, KernelBenchInputs& inputs, size_t R,
            size_t N, const RngKey& key) -> std::function<void()> {
    const auto found = calls().find(kernel);
    if (found == calls().end()) {
      throw Error("kernel benchmark: the CPU reference has no kernel '" + kernel +
                  "' (add it to bench/reference/kernel_reference.cpp)");
    }
    const Call& call = found->second;
    return [&call, &options, &inputs, R, N, key] { call(options, inputs, R, N, key); };
  };
}

}  // namespace mipnerf::bench
