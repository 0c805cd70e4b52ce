// CPU reference of kernels/rays.cl in double precision: camera rays, cone or NDC radii.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/stage_options.hpp"

namespace mipnerf::ref {

// Mirror of rays_fwd (same arguments, the packed float cameras read as doubles; outputs resized to n_rays).
// Built on camera_ray (host/data/camera.hpp) for the ray of an image position, and, independently of the
// kernel's closed forms, computes each radius literally as the official code does: the distance between the
// neighbouring pixels' directions (cone) or NDC origins (cylinder; official LLFF convert_to_ndc), times 2/√12
// (paper §3.1: the disc's per-axis variance r²/4 equals the pixel's w²/12). With options.lens_tables, a camera whose
// packed lens slot is set reads its ray from `lens_tables` ([pixels][4], data/lens_tables.hpp) as the kernel does; in
// NDC its radius is the distance between its table neighbours' NDC origins, as for a pinhole.
void rays_fwd(const RaysOptions& options, const std::vector<double>& cameras,
              const std::vector<uint32_t>& camera_ids, const std::vector<uint32_t>& pixel_ids,
              std::vector<double>& origins, std::vector<double>& directions, std::vector<double>& viewdirs,
              std::vector<double>& radii, std::vector<double>& near, std::vector<double>& far,
              std::vector<double>& lossmult, size_t n_rays, size_t n_cameras, const RngKey& key,
              const std::vector<double>& lens_tables = {});

// Official convert_to_ndc for one ray (world origin o, direction d) with the given focal lengths, image size and
// near plane: the ray shifted to the plane z = −near, then projected. Writes the NDC origin and direction. With the
// kernel's guard: |d_z| < 1e-8 (parallel to the near plane, where the official code gives Inf and NaN) is taken as
// +1e-8 if d_z > 0, else −1e-8.
void convert_to_ndc(const double o[3], const double d[3], double focal_x, double focal_y, double width, double height,
                    double near_plane, double o_ndc[3], double d_ndc[3]);

}  // namespace mipnerf::ref
