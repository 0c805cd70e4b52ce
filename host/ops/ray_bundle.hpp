// A batch (or chunk) of rays on the device, as the official code's `Rays` namedtuple: what the ray stage writes and
// the sampling, Gaussian, encoding and rendering stages read. One object instead of seven loose buffers in every
// signature. Layouts: docs/ARCHITECTURE.md, "Buffers and layouts".
#pragma once

#include <cstddef>

#include "cl/buffer.hpp"
#include "cl/context.hpp"

namespace mipnerf::ops {

struct RayBundle {
  RayBundle() = default;
  // Allocates every array for `n_rays` rays (R), named after its field and layout, e.g. "origins [R][3]".
  RayBundle(ocl::Context& ctx, size_t n_rays);

  // Device bytes the arrays of `n_rays` rays take (for memory plans): 13 floats a ray.
  static size_t bytes_for(size_t n_rays);

  // R: the rays the arrays hold. A launch may use fewer (a chunk's rays come first); each stage checks its count.
  size_t n_rays() const { return n_rays_; }

  ocl::DeviceArray<float> origins;     // [R][3] world (NDC for cylinder rays)
  ocl::DeviceArray<float> directions;  // [R][3] unnormalised, camera-frame z = −1 (NDC direction for cylinder)
  ocl::DeviceArray<float> viewdirs;    // [R][3] world direction, unit unless RaysOptions::unit_viewdirs is off;
                                       // not written without view dependence
  ocl::DeviceArray<float> radii;       // [R] cone radius at t = 1 (cylinder: radius in NDC)
  ocl::DeviceArray<float> near;        // [R] sampling range in t
  ocl::DeviceArray<float> far;         // [R]
  ocl::DeviceArray<float> lossmult;    // [R] loss weight (4^scale in multiscale data, else 1)

 private:
  size_t n_rays_ = 0;
};

}  // namespace mipnerf::ops
