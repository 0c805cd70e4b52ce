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

// gaussian_fwd's items (GAUSSIAN_SAMPLES_PER_VECTOR of gaussian.cl): one per row, or one per 16 consecutive samples of
// a ray as float16, which PoCL's CPU device runs in full-width vector registers
// (bench/results/kernel_runtimes/kernel_runtimes_xeon.md). The same floats either way, bit for bit.
enum class GaussianItems { device_default, per_row, per_vector };

class Gaussian {
 public:
  // device_default: per vector on PoCL's CPU device, per row elsewhere.
  Gaussian(ocl::Context& ctx, const GaussianOptions& options, GaussianItems items = GaussianItems::device_default);
  const GaussianOptions& options() const { return options_; }
  GaussianItems items() const { return items_; }

  // Enqueues gaussian_fwd (supplement eq. 23, or the cylinder).
  void fwd(const GaussianInputs& in, const GaussianOutputs& out);
  // Enqueues gaussian_points_fwd: means at the interval midpoints, covariances 0 (NeRF baseline).
  void points(const GaussianInputs& in, const GaussianOutputs& out);

 private:
  void check(const GaussianInputs& in, const GaussianOutputs& out, const std::string& where, bool radii) const;
  ocl::Context* ctx_;
  GaussianOptions options_;
  GaussianItems items_;  // never device_default
  ::cl::Kernel* fwd_;
  ::cl::Kernel* points_;
};

}  // namespace mipnerf::ops
