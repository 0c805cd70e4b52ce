// Host wrapper of kernels/distortion.cl: mip-NeRF 360's distortion loss (eq. 15; camp_zipnerf
// loss_utils.distortion_loss), forward and backward w.r.t. the weights and the interval edges. The training graph runs
// it on the last level of a proposal-sampled spec when LevelSpec::distortion_mult > 0 (its s-edges; their gradient
// unused).
//   loss = mult · mean over rays of Σ_{i,j} w_i w_j |u_i − u_j| + (1/3) Σ_i w_i² (t_{i+1} − t_i)
#pragma once

#include <cstddef>
#include <vector>

#include "cl/buffer.hpp"
#include "cl/context.hpp"

namespace mipnerf::ops {

// One chunk: edges t [R][N+1] (sorted; the official Zip-NeRF takes normalised s-distances, its 360 config a curve of
// t: the caller's choice) and weights w [R][N].
struct DistortionInputs {
  const ocl::DeviceArray<float>& t;
  const ocl::DeviceArray<float>& w;
  size_t n_rays;
  size_t n_intervals;
};

// mult · Σ ray_loss / batch_rays, in double, from the forward's per-ray values (downloaded).
double distortion_loss_value(const std::vector<float>& ray_loss, size_t batch_rays, float mult);

class Distortion {
 public:
  explicit Distortion(ocl::Context& ctx);

  // Enqueues distortion_fwd: ray_loss [R], each ray's eq. 15.
  void fwd(const DistortionInputs& in, ocl::DeviceArray<float>& ray_loss);
  // Enqueues distortion_bwd: d_w [R][N] and d_t [R][N+1] of mult · mean over batch_rays rays, times `upstream`
  // (overwritten, not added).
  void bwd(const DistortionInputs& in, float mult, size_t batch_rays, ocl::DeviceArray<float>& d_w,
           ocl::DeviceArray<float>& d_t, float upstream = 1.0f);

 private:
  void check(const DistortionInputs& in, const std::string& where) const;

  ocl::Context* ctx_;
  ::cl::Kernel* fwd_;
  ::cl::Kernel* bwd_;
};

}  // namespace mipnerf::ops
