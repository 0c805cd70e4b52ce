// Zip-NeRF's features of a conical frustum (Barron et al. 2023; camp_zipnerf internal/models.py predict_density,
// grid_utils.HashEncoding): its 6 multisamples (multisample.cl) looked up in every level of the grid (grid_encoding.cl),
// each level's features downweighted by the multisample's footprint against the level's cells, then, per level,
// GRID_APPEND_SCALE's extra feature (2w − 1) · level_scale[l] (w the footprint weight; level_scale[l] =
// √(maxval² + mean(table_l²)), a constant of the step: the official stop-gradient), all averaged over the
// multisamples and multiplied by `precondition` (the official precondition_scaling, 10).
//
//   rays     origins, directions [R][3], radii [R]; t_edges [R][N+1] (the level's intervals)
//   box      float4 (min x, min y, min z, size): the cube of the grid, unit_coord = (point − min) / size, and the
//            footprint's standard deviation = scale_mult · perp_radius / size (the official unscented_scale_mult 0.5)
//   features [R·N][L][GRID_FEATURES + GRID_APPEND_SCALE]
// One work-item per interval (sample): the multisamples are built once and looked up in every level.
// Reference: host/ref/zip_features.hpp (same names).

#ifndef GRID_APPEND_SCALE
#define GRID_APPEND_SCALE 1
#endif
#ifndef ZIP_CONTRACT
#define ZIP_CONTRACT 0
#endif
#define ZIP_LEVEL_WIDTH (GRID_FEATURES + GRID_APPEND_SCALE)

// A multisample (world units) in the grid's unit cube, with its footprint there. With ZIP_CONTRACT (unbounded scenes:
// the program then includes contract.cl) the point first goes through mip-NeRF 360's contraction (eq. 10: all of
// space into the ball of radius 2, the cube then [−2, 2]³) and its footprint is multiplied by the cube root of the
// contraction's Jacobian determinant there, the official's isotropic linearisation (camp_zipnerf
// coord.contract3_isoscale): with r = |x| > 1 and a = 2 − 1/r (so contract(x) = a·x/r),
//   ∛det J = ((2r − 1)²)^(1/3) / r² = ∛(a²/r) / r,
// formed from 1/r (contract_direction: |x|² is never formed, so no overflow at any finite |x|); 1 inside the ball.
inline void zip_to_unit_cube(float3 point_world, float scale_world, float4 box, float3* unit_point, float* scale) {
#if ZIP_CONTRACT
  if (contract_is_outside(point_world)) {
    float3 u;
    float inv_r;
    contract_direction(point_world, &u, &inv_r);
    const float a = 2.0f - inv_r;
    point_world = a * u;
    scale_world *= cbrt(a * a * inv_r) * inv_r;
  }
#endif
  const float inv_size = 1.0f / box.w;
  *unit_point = (point_world - box.xyz) * inv_size;
  *scale = scale_world * inv_size;
}

// The multisamples of interval `sample` (ray · N + i) in the grid's unit cube, with their footprints in its units.
inline void zip_multisamples(__global const float* origins, __global const float* directions,
                             __global const float* radii, __global const float* t_edges, uint sample,
                             uint n_intervals, float4 box, float scale_mult, ulong seed, uint step, uint first_ray,
                             float3 unit_points[ZIP_MULTISAMPLES], float scales[ZIP_MULTISAMPLES]) {
  const uint ray = sample / n_intervals, interval = sample % n_intervals;
  const float3 origin = vload3(ray, origins), direction = vload3(ray, directions);
  const size_t edge = (size_t)ray * (n_intervals + 1) + interval;
  const float t0 = t_edges[edge], t1 = t_edges[edge + 1];
#if ZIP_MULTISAMPLE
  const float radius = radii[ray];
  float3 axis1, axis2;
  perpendicular_basis(direction, &axis1, &axis2);
  bool reversed;
  float turn;
  multisample_pattern(interval, seed, step, first_ray + ray, &reversed, &turn);
  for (int j = 0; j < ZIP_MULTISAMPLES; ++j) {
    float perp;
    const float3 point = multisample_point(origin, direction, axis1, axis2, radius, t0, t1, j, reversed, turn, &perp);
    zip_to_unit_cube(point, scale_mult * perp, box, &unit_points[j], &scales[j]);
  }
#else
  const float t_mean = frustum_t_at(t0, t1, 0.0f);
#if ZIP_CYLINDER
  const float perp = 0.7071067811865476f * radii[ray];
#else
  const float perp = 0.7071067811865476f * radii[ray] * t_mean;
#endif
  zip_to_unit_cube(origin + direction * t_mean, scale_mult * perp, box, &unit_points[0], &scales[0]);
#endif
}

inline float zip_level_weight(float scale, uint4 level) {
#if GRID_DOWNWEIGHT
  return level_feature_weight(scale * (float)level.y);
#else
  return 1.0f;
#endif
}

__kernel void zip_features_fwd(__global const float* origins, __global const float* directions,
                               __global const float* radii, __global const float* t_edges,
                               __global const uint4* levels, __global const float* table,
                               __global const float* level_scale, __global float* features, const uint n_samples,
                               const uint n_intervals, const uint n_levels, const float4 box, const float scale_mult,
                               const float precondition, const ulong seed, const uint step, const uint first_ray) {
  const uint sample = get_global_id(0);
  if (sample >= n_samples) return;
  float3 points[ZIP_MULTISAMPLES];
  float scales[ZIP_MULTISAMPLES];
  zip_multisamples(origins, directions, radii, t_edges, sample, n_intervals, box, scale_mult, seed, step, first_ray,
                   points, scales);
  const float mean = precondition / (float)ZIP_MULTISAMPLES;
  __global float* out = features + (size_t)sample * n_levels * ZIP_LEVEL_WIDTH;
  for (uint l = 0; l < n_levels; ++l) {
    const uint4 level = levels[l];
    float sum[ZIP_LEVEL_WIDTH];
    for (int f = 0; f < ZIP_LEVEL_WIDTH; ++f) sum[f] = 0.0f;
    for (int j = 0; j < ZIP_MULTISAMPLES; ++j) {
      const GridCorners c = grid_corners(level, points[j]);
      const float weight = zip_level_weight(scales[j], level);
      for (int corner = 0; corner < 8; ++corner) {
        if (c.entry[corner] < 0) continue;
        const float w = weight * c.weight[corner];
        for (int f = 0; f < GRID_FEATURES; ++f) sum[f] += w * table[c.entry[corner] * GRID_FEATURES + f];
      }
#if GRID_APPEND_SCALE
      sum[GRID_FEATURES] += (2.0f * weight - 1.0f) * level_scale[l];
#endif
    }
    for (int f = 0; f < ZIP_LEVEL_WIDTH; ++f) out[l * ZIP_LEVEL_WIDTH + f] = mean * sum[f];
  }
}

// The mean's gradient at one level of one interval: mean · d_features (false when it is all zero: nothing to add).
inline bool zip_level_gradient(__global const float* d_level, float mean, float d_mean[GRID_FEATURES]) {
  bool any = false;
  for (int f = 0; f < GRID_FEATURES; ++f) {
    d_mean[f] = mean * d_level[f];
    any = any || d_mean[f] != 0.0f;
  }
  return any;
}

// d_table += d_mean spread onto the corners of every multisample of one interval at one level, each term weighted by
// the multisample's level weight and its corner's trilinear weight: the scatter both backward kernels share. `atomic`
// is a constant of each call site, so the branch folds away.
inline void zip_scatter_level(__global float* d_table, uint4 level, const float3 points[ZIP_MULTISAMPLES],
                              const float scales[ZIP_MULTISAMPLES], const float d_mean[GRID_FEATURES], bool atomic) {
  for (int j = 0; j < ZIP_MULTISAMPLES; ++j) {
    const GridCorners c = grid_corners(level, points[j]);
    const float weight = zip_level_weight(scales[j], level);
    for (int corner = 0; corner < 8; ++corner) {
      if (c.entry[corner] < 0) continue;
      const float w = weight * c.weight[corner];
      __global float* entry = d_table + c.entry[corner] * GRID_FEATURES;
      for (int f = 0; f < GRID_FEATURES; ++f) {
        const float g = w * d_mean[f];
        if (!atomic) {
          entry[f] += g;
        } else if (g != 0.0f) {
          atomic_add_float(&entry[f], g);
        }
      }
    }
  }
}

// d_table += the features' gradients spread onto the corners of every multisample (atomic_add_float: its order
// bound is grid_encoding.cl's). The scale feature has no table gradient (the official stop-gradient).
__kernel void zip_features_bwd(__global const float* origins, __global const float* directions,
                               __global const float* radii, __global const float* t_edges,
                               __global const uint4* levels, __global const float* d_features,
                               __global float* d_table, const uint n_samples, const uint n_intervals,
                               const uint n_levels, const float4 box, const float scale_mult, const float precondition,
                               const ulong seed, const uint step, const uint first_ray) {
  const uint sample = get_global_id(0);
  if (sample >= n_samples) return;
  float3 points[ZIP_MULTISAMPLES];
  float scales[ZIP_MULTISAMPLES];
  zip_multisamples(origins, directions, radii, t_edges, sample, n_intervals, box, scale_mult, seed, step, first_ray,
                   points, scales);
  const float mean = precondition / (float)ZIP_MULTISAMPLES;
  __global const float* d_out = d_features + (size_t)sample * n_levels * ZIP_LEVEL_WIDTH;
  for (uint l = 0; l < n_levels; ++l) {
    float d_mean[GRID_FEATURES];
    if (zip_level_gradient(d_out + l * ZIP_LEVEL_WIDTH, mean, d_mean)) {
      zip_scatter_level(d_table, levels[l], points, scales, d_mean, true);
    }
  }
}

// The same gradient, deterministic: one work-item per level walks every sample in order and adds without atomics (no
// other work-item writes that level's entries). The order is fixed, so a run and its resume sum bit for bit alike;
// only n_levels work-items run, which suits a CPU device with a few cores (the atomic kernel there spends its time in
// compare-and-swap retries on the coarse levels, where thousands of samples share a cell), not a GPU.
__kernel void zip_features_bwd_by_level(__global const float* origins, __global const float* directions,
                                        __global const float* radii, __global const float* t_edges,
                                        __global const uint4* levels, __global const float* d_features,
                                        __global float* d_table, const uint n_samples, const uint n_intervals,
                                        const uint n_levels, const float4 box, const float scale_mult,
                                        const float precondition, const ulong seed, const uint step,
                                        const uint first_ray) {
  const uint l = get_global_id(0);
  if (l >= n_levels) return;
  const uint4 level = levels[l];
  const float mean = precondition / (float)ZIP_MULTISAMPLES;
  for (uint sample = 0; sample < n_samples; ++sample) {
    float d_mean[GRID_FEATURES];
    if (!zip_level_gradient(d_features + ((size_t)sample * n_levels + l) * ZIP_LEVEL_WIDTH, mean, d_mean)) continue;
    float3 points[ZIP_MULTISAMPLES];
    float scales[ZIP_MULTISAMPLES];
    zip_multisamples(origins, directions, radii, t_edges, sample, n_intervals, box, scale_mult, seed, step, first_ray,
                     points, scales);
    zip_scatter_level(d_table, level, points, scales, d_mean, false);
  }
}

// level_scale[l] = √(maxval² + mean over level l's table of value²): the scale feature's factor (the official
// `f_scale`, whose stop-gradient makes it a constant of the step). One work-item per level; the sum in double when
// the device has it would not change the float it ends as by more than the order error, so float it is, in order.
__kernel void zip_level_scale(__global const uint4* levels, __global const float* table,
                              __global float* level_scale, const uint n_levels, const float maxval) {
  const uint l = get_global_id(0);
  if (l >= n_levels) return;
  const uint4 level = levels[l];
  const size_t first = (size_t)level.x * GRID_FEATURES, count = (size_t)level.z * GRID_FEATURES;
  float sum = 0.0f, compensation = 0.0f;  // Kahan: a hashed level has millions of terms
  for (size_t i = 0; i < count; ++i) {
    const float term = table[first + i] * table[first + i] - compensation;
    const float next = sum + term;
    compensation = (next - sum) - term;
    sum = next;
  }
  level_scale[l] = sqrt(maxval * maxval + sum / (float)count);
}

// The official param_regularizers' gradient, added: mult · ½ · mean(table_l²) per level has the gradient
// mult · value / count_l on each of level l's values (count_l = its entries × features). One work-item per value.
__kernel void grid_weight_decay(__global const uint4* levels, __global const float* table, __global float* d_table,
                                const uint n_levels, const float mult) {
  const uint i = get_global_id(0);
  const uint4 last = levels[n_levels - 1];
  if (i >= (last.x + last.z) * GRID_FEATURES) return;
  uint l = 0;
  while (l + 1 < n_levels && i >= levels[l + 1].x * GRID_FEATURES) ++l;
  d_table[i] += mult * table[i] / (float)(levels[l].z * GRID_FEATURES);
}
