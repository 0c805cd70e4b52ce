// CPU reference (double) of Zip-NeRF's multisamples (camp_zipnerf internal/coord.py `hexify`): the 6 points that
// stand for one conical frustum, spread over its shape so that their mean and covariance match the frustum's
// (mip-NeRF's moments: the first paper's eq. 7-8). Each point's grid features are then looked up and averaged. This
// is the deterministic pattern (the official `rng=None`, used at render time): interval i's hexagon has the angles
// (π/3)·(0, 2, 4, 3, 5, 1), reversed and turned by π/6 for odd i. Pinned by tests/official/test_grid_encoding.cpp.
#pragma once

#include <array>

namespace mipnerf::ref {

using Vec3d = std::array<double, 3>;

// Two unit vectors perpendicular to `direction` and to each other: direction × (0, 0, 1), or × (1, 1, 1) when the
// first is (nearly) zero (every component below float32's ε), then direction × that (coord.construct_perp_basis).
std::array<Vec3d, 2> perpendicular_basis(const Vec3d& direction);

struct Multisamples {
  std::array<Vec3d, 6> points_world;
  std::array<double, 6> perp_radius;  // each point's distance from the ray axis, in direction-length units
};

// The 6 multisamples of interval [t0, t1] (index `interval`, for the pattern's parity) of a ray with `origin`,
// unnormalised `direction` and cone radius `radius` at t = 1: along the ray at t_j = t0 + d/(d² + 3s²) ·
// ((t1² + 2s²) + 3/√7 · (2j/5 − 1) · √((d² − s²)² + 4s⁴)), s, d the interval's midpoint and half-width, and
// √½ · radius · t_j off the axis at the hexagon's angles.
Multisamples hexify_multisamples(const Vec3d& origin, const Vec3d& direction, double radius, double t0, double t1,
                                 int interval);

// Any pattern of the hexagon: its angles' order reversed or not, then turned by `turn` radians (training draws both per
// interval, kernels/multisample.cl; the deterministic pattern is reversed = odd interval, turn = π/6 then). A
// cylinder's points sit √½ · radius off the axis whatever t (NDC rays, whose footprint does not grow along the ray).
Multisamples hexify_multisamples(const Vec3d& origin, const Vec3d& direction, double radius, double t0, double t1,
                                 bool reversed, double turn, bool cylinder);

}  // namespace mipnerf::ref
