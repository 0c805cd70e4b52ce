// Zip-NeRF's deterministic hexagonal multisamples in double precision (multisample.hpp).
#include "ref/multisample.hpp"

#include <cmath>

namespace mipnerf::ref {
namespace {

Vec3d cross(const Vec3d& a, const Vec3d& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

Vec3d normalized(const Vec3d& v) {
  const double length = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  return {v[0] / length, v[1] / length, v[2] / length};
}

}  // namespace

std::array<Vec3d, 2> perpendicular_basis(const Vec3d& direction) {
  const double float_epsilon = 1.1920928955078125e-07;  // np.finfo(np.float32).eps
  Vec3d first = cross(direction, {0.0, 0.0, 1.0});
  if (std::abs(first[0]) < float_epsilon && std::abs(first[1]) < float_epsilon && std::abs(first[2]) < float_epsilon) {
    first = cross(direction, {1.0, 1.0, 1.0});
  }
  const Vec3d second = cross(direction, first);
  return {normalized(first), normalized(second)};
}

Multisamples hexify_multisamples(const Vec3d& origin, const Vec3d& direction, double radius, double t0, double t1,
                                 int interval) {
  const bool odd = interval % 2 != 0;
  return hexify_multisamples(origin, direction, radius, t0, t1, odd, odd ? M_PI / 6 : 0.0, false);
}

Multisamples hexify_multisamples(const Vec3d& origin, const Vec3d& direction, double radius, double t0, double t1,
                                 bool reversed, double turn, bool cylinder) {
  static const int kOrder[6] = {0, 2, 4, 3, 5, 1};
  const auto basis = perpendicular_basis(direction);
  const double s = 0.5 * (t0 + t1), d = 0.5 * (t1 - t0);
  const double denominator = d * d + 3 * s * s;
  const double scale = std::abs(denominator) < 1.1754943508222875e-38 ? 0.0 : d / denominator;  // math.safe_div's guard (float32 tiny)
  const double spread = std::sqrt((d * d - s * s) * (d * d - s * s) + 4 * s * s * s * s);
  Multisamples out;
  for (int j = 0; j < 6; ++j) {
    const double t = t0 + scale * ((t1 * t1 + 2 * s * s) + (3 / std::sqrt(7.0)) * (j * 0.4 - 1) * spread);
    const double theta = (M_PI / 3) * kOrder[reversed ? 5 - j : j] + turn;
    const double perp = std::sqrt(0.5) * radius * (cylinder ? 1.0 : t);
    out.perp_radius[j] = perp;
    for (int a = 0; a < 3; ++a) {
      out.points_world[j][a] = origin[a] + basis[0][a] * perp * std::cos(theta) +
                               basis[1][a] * perp * std::sin(theta) + direction[a] * t;
    }
  }
  return out;
}

}  // namespace mipnerf::ref
