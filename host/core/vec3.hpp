// 3-vectors in double precision for host-side geometry (poses, camera paths, the procedural scene): the one set of
// helpers every floor above uses, instead of a copy per file.
#pragma once

#include <array>
#include <cmath>

namespace mipnerf {

using Vec3 = std::array<double, 3>;

inline Vec3 add(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline Vec3 scale(const Vec3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
inline double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double length(const Vec3& v) { return std::sqrt(dot(v, v)); }
// v / |v|: not finite for a zero vector (callers that can meet one check first).
inline Vec3 normalize(const Vec3& v) { return scale(v, 1.0 / length(v)); }
inline bool is_finite(const Vec3& v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

}  // namespace mipnerf
