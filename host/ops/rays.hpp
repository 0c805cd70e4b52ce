// Host wrapper of kernels/rays.cl: camera rays with cone (or NDC) radii for a batch of (camera, pixel) pairs.
#pragma once

#include <cstddef>
#include <cstdint>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "cl/program.hpp"
#include "core/stage_options.hpp"
#include "ops/ray_bundle.hpp"

namespace mipnerf::ops {

// RAY_SHAPE, PIXEL_CENTER_OFFSET, SUBPIXEL_JITTER, VIEW_DEPENDENCE, UNIT_VIEWDIRS, LENS_TABLES, NDC_NEAR_PLANE.
ocl::BuildOptions rays_build_options(const RaysOptions& options);

struct RaysInputs {
  const ocl::DeviceArray<float>& cameras;        // [C][24] packed (pack_cameras)
  const ocl::DeviceArray<uint32_t>& camera_ids;  // [R]
  const ocl::DeviceArray<uint32_t>& pixel_ids;   // [R] y·width + x
  size_t n_rays;
  // The cameras' lens tables ([pixels][4], data/lens_tables.hpp), needed by (and only by) a stage built with
  // RaysOptions::lens_tables; cameras whose packed lens slot is 0 ignore them.
  const ocl::DeviceArray<float>* lens_tables = nullptr;
};

// The ray stage for one specialisation (built on construction).
class Rays {
 public:
  Rays(ocl::Context& ctx, const RaysOptions& options);
  const RaysOptions& options() const { return options_; }

  // Enqueues rays_fwd: rays 0 .. in.n_rays − 1 of `out` (every array but viewdirs without view dependence).
  // `key` matters only with jitter_subpixel. A camera id ≥ C or a pixel id outside its image gives NaN in every
  // output of that ray. Throws mipnerf::Error for undersized buffers.
  void fwd(const RaysInputs& in, RayBundle& out, const RngKey& key = {});

 private:
  ocl::Context* ctx_;
  RaysOptions options_;
  ocl::DeviceArray<float> no_lens_tables_;  // bound in the lens tables' place when there are none
  ::cl::Kernel* fwd_;
};

}  // namespace mipnerf::ops
