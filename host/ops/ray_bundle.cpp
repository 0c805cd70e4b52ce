// A batch of rays on the device (see ray_bundle.hpp).
#include "ops/ray_bundle.hpp"

namespace mipnerf::ops {
namespace {

// Floats per ray: origins, directions and viewdirs (3 each), then radii, near, far and lossmult (1 each).
constexpr size_t kFloatsPerRay = 3 * 3 + 4;

}  // namespace

RayBundle::RayBundle(ocl::Context& ctx, size_t n_rays)
    : origins(ctx, 3 * n_rays, "origins [R][3]"),
      directions(ctx, 3 * n_rays, "directions [R][3]"),
      viewdirs(ctx, 3 * n_rays, "viewdirs [R][3]"),
      radii(ctx, n_rays, "radii [R]"),
      near(ctx, n_rays, "near [R]"),
      far(ctx, n_rays, "far [R]"),
      lossmult(ctx, n_rays, "ray lossmult [R]"),
      n_rays_(n_rays) {}

size_t RayBundle::bytes_for(size_t n_rays) { return kFloatsPerRay * n_rays * sizeof(float); }

}  // namespace mipnerf::ops
