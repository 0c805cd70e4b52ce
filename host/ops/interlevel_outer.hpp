// Host wrapper of kernels/interlevel_outer.cl: mip-NeRF 360's interlevel loss of one proposal round against the
// NeRF's final histogram (multinerf stepfun.lossfun_outer, train_utils.interlevel_loss), forward and backward: the
// loss of mip-NeRF's proposal rounds (graph.hpp, LevelRole::proposal with InterlevelKind::outer).
//
//   bound_j = Σ of the proposal weights over the intervals that overlap NeRF interval j   (the outer measure)
//   loss    = mult · mean_{rays, j} max(0, w_j − bound_j)² / (w_j + ε)
// The NeRF's (c, w) take no gradient (the official stop-gradient); the backward is ∂loss/∂wp.
#pragma once

#include <cstddef>
#include <vector>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "ops/interlevel.hpp"

namespace mipnerf::ops {

// mult · Σ ray_loss / (batch_rays · N): the round's loss from the forward's per-ray sums (downloaded), in double.
// (The mean runs over the NeRF's N intervals, where the spline loss's runs over the round's M.)
double outer_interlevel_loss_value(const std::vector<float>& ray_loss, size_t batch_rays, size_t n_intervals,
                                   float mult);

class OuterInterlevel {
 public:
  explicit OuterInterlevel(ocl::Context& ctx);

  // Enqueues outer_interlevel_fwd: ray_loss [R] = Σ_j of the NeRF intervals' losses. Throws mipnerf::Error for a
  // buffer too small or an empty histogram shape.
  void fwd(const InterlevelInputs& in, ocl::DeviceArray<float>& ray_loss);
  // Enqueues outer_interlevel_bwd: d_wp [R][M] = ∂loss/∂wp for a batch of batch_rays rays (this chunk's share), times
  // `upstream` (1 for the loss itself).
  void bwd(const InterlevelInputs& in, float mult, size_t batch_rays, ocl::DeviceArray<float>& d_wp,
           float upstream = 1.0f);

 private:
  ocl::Context* ctx_;
  ::cl::Kernel* fwd_;
  ::cl::Kernel* bwd_;
};

}  // namespace mipnerf::ops
