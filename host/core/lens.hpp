// Lens distortion as COLMAP models it (src/colmap/sensor/models.h; the models read here are the rows of
// core/lens_models.hpp), on normalised image coordinates: a point at (x, y, z) in the camera's OpenCV frame (x right, y down, z forward)
// projects to u = x/z, v = y/z; the lens moves (u, v) to (u_d, v_d); the pixel is (fx·u_d + cx, fy·v_d + cy).
// Resizing an image changes fx, fy, cx, cy, not the lens. Rays go the other way: a pixel's (u_d, v_d) is
// undistorted by Newton's method, as COLMAP's IterativeUndistortion does (in double precision here).
#pragma once

#include <array>
#include <string>

namespace mipnerf {

enum class LensModel {
  pinhole,         // no distortion
  simple_radial,   // COLMAP SIMPLE_RADIAL: u_d = u·(1 + k1·r²)
  radial,          // COLMAP RADIAL: u_d = u·(1 + k1·r² + k2·r⁴)
  opencv,          // COLMAP OPENCV: radial k1, k2 and tangential p1, p2
  opencv_fisheye,  // COLMAP OPENCV_FISHEYE: θ = atan(r), θ_d = θ·(1 + k1·θ² + k2·θ⁴ + k3·θ⁶ + k4·θ⁸), u_d = u·θ_d/r
  full_opencv,     // COLMAP FULL_OPENCV: OPENCV with the rational radial factor (1 + k1·r² + k2·r⁴ + k3·r⁶) /
                   // (1 + k4·r² + k5·r⁴ + k6·r⁶)
};

// The coefficients of every model; the ones a model takes, and their COLMAP order, are its row's
// (core/lens_models.hpp); the others stay 0.
struct Lens {
  LensModel model = LensModel::pinhole;
  double k1 = 0, k2 = 0, k3 = 0, k4 = 0;  // radial (fisheye: k1..k4 of θ; full_opencv: k4 starts the denominator)
  double p1 = 0, p2 = 0;                  // tangential (opencv, full_opencv)
  double k5 = 0, k6 = 0;                  // full_opencv's denominator
  bool is_pinhole() const { return model == LensModel::pinhole; }
};

// COLMAP's name of the model ("PINHOLE" for none, "SIMPLE_RADIAL", …): its row's.
const char* lens_model_name(LensModel model);

using Uv = std::array<double, 2>;

// The lens applied to normalised coordinates (u, v) → (u_d, v_d).
Uv distort(const Lens& lens, const Uv& uv);

// The (u, v) that `lens` moves to `distorted`: Newton's method from (u_d, v_d), with the Jacobian by central
// differences (as COLMAP), until the step is below 1e-14 (at most 100 iterations). Returns false when it does not
// converge, the result does not map back to `distorted` within 1e-12, or it lies beyond a fold of the lens (the
// Jacobian's determinant is not positive somewhere between the centre and it): the lens has no ray for that point.
bool undistort(const Lens& lens, const Uv& distorted, Uv& uv);

// Throws mipnerf::Error naming `where` when a coefficient is not finite.
void check_lens(const Lens& lens, const std::string& where);

}  // namespace mipnerf
