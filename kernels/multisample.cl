// Zip-NeRF's multisamples (Barron et al. 2023, §2; camp_zipnerf internal/coord.py `hexify`): 6 points standing for
// one conical frustum, spread over its shape so that their mean and covariance match the frustum's (mip-NeRF's
// moments, the first paper's eq. 7-8), each point's grid features then looked up and averaged (zip_features.cl).
// Along the ray: t_j = t0 + d/(d² + 3s²) · ((t1² + 2s²) + 3/√7 · (2j/5 − 1) · √((d² − s²)² + 4s⁴)), s and d the
// interval's midpoint and half-width; off the axis: √½ · radius · t_j (cone) or √½ · radius (ZIP_CYLINDER: NDC rays,
// whose footprint does not grow with t) at the hexagon's angles (π/3)·(0, 2, 4, 3, 5, 1): a hexagon's points at
// radius ρ have a variance of ρ²/2 per axis, the frustum's r²t²/4. Reference: host/ref/multisample.hpp.
// Rendering uses the deterministic pattern (odd intervals reversed and turned by π/6); training turns each interval's
// hexagon by a uniform angle and reverses half of them (ZIP_RANDOMIZED), keyed by (seed, step, ray, interval).

#ifndef ZIP_CYLINDER
#define ZIP_CYLINDER 0
#endif

#ifndef ZIP_RANDOMIZED
#define ZIP_RANDOMIZED 0
#endif

#ifndef ZIP_MULTISAMPLE
#define ZIP_MULTISAMPLE 1
#endif

// ZIP_MULTISAMPLE 0 looks up one point per interval, the frustum's mean on the axis (mip-NeRF's t_μ), with the
// footprint the hexagon's points would have there (√½·radius·t_μ, or √½·radius for cylinders): without
// GRID_DOWNWEIGHT a plain grid's lookup, the comparison Zip-NeRF's anti-aliasing is measured against; with it, the
// footprint-weighted levels at a sixth of the lookups.
#if ZIP_MULTISAMPLE
#define ZIP_MULTISAMPLES 6
#else
#define ZIP_MULTISAMPLES 1
#endif
#define RNG_STREAM_MULTISAMPLE 5u /* turn and reversal of each interval's hexagon (training) */

// Two unit vectors perpendicular to `direction` and each other: direction × ẑ, or × (1, 1, 1) when that is (nearly)
// zero, then direction × the first (coord.construct_perp_basis).
inline void perpendicular_basis(float3 direction, float3* axis1, float3* axis2) {
  float3 first = cross(direction, (float3)(0.0f, 0.0f, 1.0f));
  if (all(fabs(first) < FLT_EPSILON)) first = cross(direction, (float3)(1.0f, 1.0f, 1.0f));
  *axis1 = normalize(first);
  *axis2 = normalize(cross(direction, first));
}

// Where along the ray the point of [t0, t1] at `offset` = 2j/5 − 1 ∈ [−1, 1] sits (the formula above, in mip-NeRF's
// stable form); offset 0 is the frustum's mean t_μ = s + 2sd²/(3s² + d²).
inline float frustum_t_at(float t0, float t1, float offset) {
  const float s = 0.5f * (t0 + t1), d = 0.5f * (t1 - t0);
  const float denominator = d * d + 3.0f * s * s;
  const float scale = denominator < FLT_MIN ? 0.0f : d / denominator;  // math.safe_div's guard
  const float spread = sqrt((d * d - s * s) * (d * d - s * s) + 4.0f * s * s * s * s);
  return t0 + scale * ((t1 * t1 + 2.0f * s * s) + 1.1338934190276817f * offset * spread);
}

// Where along the ray multisample j of [t0, t1] sits.
inline float multisample_t(float t0, float t1, int j) { return frustum_t_at(t0, t1, (float)j * 0.4f - 1.0f); }

// The hexagon's angle of multisample j: the official order, reversed or not, turned by `turn` radians.
inline float multisample_angle(int j, bool reversed, float turn) {
  const int order[6] = {0, 2, 4, 3, 5, 1};
  return 1.0471975511965976f * (float)order[reversed ? 5 - j : j] + turn;
}

// The pattern of interval `interval` of ray `ray_number`: reversed or not, and its turn.
inline void multisample_pattern(uint interval, ulong seed, uint step, uint ray_number, bool* reversed, float* turn) {
#if ZIP_RANDOMIZED
  const float4 u = rng_uniform4(seed, ray_number, step, interval, RNG_STREAM_MULTISAMPLE);
  *reversed = u.x < 0.5f;
  *turn = 6.283185307179586f * u.y;
#else
  *reversed = (interval & 1u) != 0u;
  *turn = *reversed ? 0.5235987755982988f : 0.0f;
#endif
}

// Multisample j: its point (ray coordinates) and its distance from the axis.
inline float3 multisample_point(float3 origin, float3 direction, float3 axis1, float3 axis2, float radius, float t0,
                                float t1, int j, bool reversed, float turn, float* perp_radius) {
  const float t = multisample_t(t0, t1, j);
#if ZIP_CYLINDER
  const float perp = 0.7071067811865476f * radius;
#else
  const float perp = 0.7071067811865476f * radius * t;
#endif
  const float angle = multisample_angle(j, reversed, turn);
  *perp_radius = perp;
  return origin + axis1 * (perp * cos(angle)) + axis2 * (perp * sin(angle)) + direction * t;
}
