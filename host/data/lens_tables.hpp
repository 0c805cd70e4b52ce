// Where each pixel's ray goes behind a lens, computed once per camera in double precision and read by the ray kernel
// (kernels/rays.cl, LENS_TABLES): for every pixel the undistorted normalised coordinates (u, v) of its centre, and its
// cone radius at unit depth from its own footprint — the mean distance from its undistorted centre to those of its
// right and lower neighbours (left and upper in the last column and row) × 2/√12 — so a pixel at a fisheye's rim gets
// the wider cone it really covers. Cameras with the same lens, intrinsics and size share one table.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/camera.hpp"

namespace mipnerf::data {

struct LensTables {
  std::vector<float> values;        // [pixels of every table][4]: u, v (OpenCV frame, y down), radius, 0
  std::vector<uint32_t> table_of;   // [C]: the camera's table offset in float4 elements + 1; 0: a pinhole camera
  bool empty() const { return values.empty(); }
};

// Tables for the cameras behind a lens (`names[c]` names camera c in errors, e.g. its image file). Throws
// mipnerf::Error naming the camera when its lens cannot be inverted at some pixel (the lens folds the image there:
// not a lens COLMAP would estimate; check the coefficients).
LensTables build_lens_tables(const std::vector<Camera>& cameras, const std::vector<std::string>& names = {});

// The check load_dataset makes of every lens camera, before any table is built: the coefficients are finite and the
// lens inverts at every pixel of the image's border and centre lines (the radial profiles fold, if at all, beyond some
// radius, so the border is where an image first leaves the lens). Throws mipnerf::Error naming `name` and the pixel.
void check_lens_over_image(const Camera& camera, const std::string& name);

// Writes each camera's table slot into its packed camera (camera_layout::lens_table, as the bits of a uint).
void set_lens_table_slots(std::vector<float>& packed_cameras, const LensTables& tables);

// The largest displacement, in pixels, the lens makes over the image (its border and centre lines): what `dataset
// inspect` reports. 0 for a pinhole camera.
double largest_distortion_px(const Camera& camera);

}  // namespace mipnerf::data
