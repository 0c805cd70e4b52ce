// Host wrapper of kernels/gaussian.cl: interval → Gaussian (conical frustum or cylinder), and point samples.
#pragma once

#include <cstddef>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "cl/program.hpp"
#include "core/stage_options.hpp"
#include "ops/ray_bundle.hpp"

namespace mipnerf::ops {

ocl::BuildOptions gaussian_build_options(const GaussianOptions& options);  // RAY_SHAPE

struct GaussianInputs {
  const RayBundle& rays;                   // reads origins, directions and radii (radii not by points())
  const ocl::DeviceArray<float>& t_edges;  // [R][N+1]
  size_t n_rays;                           // R ≤ rays.n_rays(): the bundle's first R rays
  size_t n_samples;                        // N
};

struct GaussianOutputs {
  ocl::DeviceArray<float>& means;  // [R][N][3] world
  ocl::DeviceArray<float>& covs;   // [R][N][3] diagonal covariance
};

class Gaussian {
 public:
  Gaussian(ocl::Context& ctx, const GaussianOptions& options);
  const GaussianOptions& options() const { return options_; }

  // Enqueues gaussian_fwd (supplement eq. 23, or the cylinder).
  void fwd(const GaussianInputs& in, const GaussianOutputs& out);
  // Enqueues gaussian_points_fwd: means at the interval midpoints, covariances 0 (NeRF baseline).
  void points(const GaussianInputs& in, const GaussianOutputs& out);

 private:
  void check(const GaussianInputs& in, const GaussianOutputs& out, const std::string& where, bool radii) const;
  ocl::Context* ctx_;
  GaussianOptions options_;
  ::cl::Kernel* fwd_;
  ::cl::Kernel* points_;
};

}  // namespace mipnerf::ops
