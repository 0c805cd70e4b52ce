// Host wrapper of kernels/interlevel.cl: Zip-NeRF's anti-aliased ("spline") interlevel loss of one proposal round
// against the NeRF's final histogram (camp_zipnerf loss_utils.spline_interlevel_loss), forward and backward: the loss
// of the training graph's proposal rounds (graph.hpp, LevelRole::proposal).
//
//   w_blur = (c, w) as a pdf, blurred by a box of half-width r, integrated over each proposal interval of cp
//   loss   = mult · mean_{rays, j} max(0, w_blur_j − wp_j)² / (wp_j + ε)
// The NeRF's (c, w) take no gradient (the official stop-gradient); the backward is ∂loss/∂wp.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "cl/buffer.hpp"
#include "cl/context.hpp"

namespace mipnerf::ops {

// Which interlevel loss a proposal round takes.
enum class InterlevelKind {
  spline,  // Zip-NeRF's anti-aliased loss (this file): the NeRF's histogram blurred, resampled into the round's
  outer,   // mip-NeRF 360's eq. 13 (ops/interlevel_outer.hpp): the round's outer measure must bound the NeRF's weights
};

// One round's constants (the official Zip-NeRF config: mults 0.01, blurs (0.03, 0.003) over its two rounds; mip-NeRF
// 360's: the outer loss, mult 1).
struct InterlevelRound {
  InterlevelKind kind = InterlevelKind::spline;
  float blur_halfwidth = 0.03f;  // r, in the normalised s-distance of c and cp; must be > 0 (spline only)
  float mult = 0.01f;            // the round's loss multiplier
};

// One chunk of rays: the NeRF's histogram (c [R][N+1], w [R][N]) and the round's (cp [R][M+1], wp [R][M]), edges
// sorted along each ray.
struct InterlevelInputs {
  const ocl::DeviceArray<float>& c;
  const ocl::DeviceArray<float>& w;
  const ocl::DeviceArray<float>& cp;
  const ocl::DeviceArray<float>& wp;
  size_t n_rays;
  size_t n_intervals;  // N
  size_t n_proposal;   // M
};

// mult · Σ ray_loss / (batch_rays · M): the round's loss from the forward's per-ray sums (downloaded), in double.
double interlevel_loss_value(const std::vector<float>& ray_loss, size_t batch_rays, size_t n_proposal, float mult);

namespace detail {
// Both interlevel losses' checks of a chunk's histograms (shapes and buffer sizes), naming `where`.
void check_interlevel_inputs(const InterlevelInputs& in, const std::string& where);
// mult · Σ ray_loss / (batch_rays · intervals) in double: a round's loss as a mean over `intervals` per ray.
double mean_interlevel_loss(const std::vector<float>& ray_loss, size_t batch_rays, size_t intervals, float mult,
                            const std::string& what);
}  // namespace detail

class SplineInterlevel {
 public:
  explicit SplineInterlevel(ocl::Context& ctx);

  // Enqueues spline_interlevel_fwd: w_blur [R][M] (the backward's input) and ray_loss [R] = Σ_j of the interval
  // losses. Throws mipnerf::Error for a buffer too small, an empty histogram shape or a half-width that is not > 0.
  void fwd(const InterlevelInputs& in, float blur_halfwidth, ocl::DeviceArray<float>& w_blur,
           ocl::DeviceArray<float>& ray_loss);
  // Enqueues spline_interlevel_bwd: d_wp [R][M] = ∂loss/∂wp for a batch of batch_rays rays (this chunk's share),
  // times `upstream` (1 for the loss itself).
  void bwd(const InterlevelInputs& in, const ocl::DeviceArray<float>& w_blur, float mult, size_t batch_rays,
           ocl::DeviceArray<float>& d_wp, float upstream = 1.0f);

 private:
  ocl::Context* ctx_;
  ::cl::Kernel* fwd_;
  ::cl::Kernel* bwd_;
};

}  // namespace mipnerf::ops
