// Host wrapper of kernels/contracted_ipe.cl: mip-NeRF 360's encoding of frustums — the full Gaussian through the
// contraction, projected onto the tessellated icosahedron's directions (core/geodesic_basis.hpp), then IPE (official
// MLP.predict_density with warp_fn = coord.contract). Forward only: nothing trained lies before it.
#pragma once

#include <cstddef>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "core/stage_options.hpp"
#include "ops/gaussian.hpp"

namespace mipnerf::ops {

// Features per row for `encoding`'s degrees on the basis of `tessellation`: 2·L·K (official: 2·12·21 = 504).
size_t contracted_ipe_width(const EncodingOptions& encoding, int tessellation);

class ContractedIpe {
 public:
  // The basis of `tessellation` (official basis_subdivisions = 2: 21 directions) is uploaded once. `sincos_every` (1..8)
  // is CONTRACTED_IPE_SINCOS_EVERY: one sincos every that many degrees, the others by angle doubling; 0: the device's
  // default, 4 on CPUs (1.7x faster on PoCL's, 2 cores of an AMD EPYC: 452 against 765 ns a row of 504 features, one
  // run side by side) and 1 elsewhere, as encode.cpp chooses for the IPE.
  ContractedIpe(ocl::Context& ctx, const GaussianOptions& options, int tessellation = 2, int sincos_every = 0);
  size_t n_basis() const { return n_basis_; }
  int sincos_every() const { return sincos_every_; }
  size_t width(const EncodingOptions& encoding) const;

  // Enqueues contracted_ipe_fwd: features [R·N][width(encoding)] from the rays and t_edges of `in`.
  void fwd(const EncodingOptions& encoding, const GaussianInputs& in, ocl::DeviceArray<float>& features);

 private:
  ocl::Context* ctx_;
  size_t n_basis_;
  int sincos_every_;
  ocl::DeviceArray<float> basis_;  // [K][3]
  ::cl::Kernel* fwd_;
};

}  // namespace mipnerf::ops
