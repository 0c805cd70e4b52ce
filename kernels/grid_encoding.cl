// Zip-NeRF's multi-resolution grid encoding (Barron et al. 2023; camp_zipnerf internal/grid_utils.py,
// hash_resample.py, resample.py), forward and backward: each point's features at every level, trilinearly
// interpolated from the 8 cells around it, each level's features scaled by how much of the point's Gaussian falls in
// one of its cells (GRID_DOWNWEIGHT: the anti-aliasing that keeps mip-NeRF's, as IPE fades frequencies).
//
//   levels  [L][4] uint: the level's first table entry, its size N (cells a side), its table size T (entries),
//           hashed (1: N³ > T, the slot is (x ⊕ y·19349663 ⊕ z·83492791) mod T in uint32; 0: a dense N³ grid
//           indexed [x][y][z], zero outside it)
//   coords  [P][3] the points in the unit cube ([0, 1]³; outside it the hash wraps and the dense grid reads zero)
//   scales  [P] the Gaussian's standard deviation in the same units (read only with GRID_DOWNWEIGHT)
//   table   [entries][GRID_FEATURES]; features [P][L][GRID_FEATURES]
// Cell centres sit at half-integers of x·N (half_pixel_center in the official code). Reference:
// host/ref/grid_encoding.hpp (same names). One work-item per (point, level).

#ifndef GRID_FEATURES
#define GRID_FEATURES 2
#endif
#ifndef GRID_DOWNWEIGHT
#define GRID_DOWNWEIGHT 1
#endif

// The 8 corners of a point at one level: table entry (or -1 for a dense cell outside the grid) and weight.
typedef struct {
  int entry[8];
  float weight[8];
} GridCorners;

// Cells beyond ±2^30 are clamped there first so the float → int conversion stays defined; the official code's wrap
// of such cells is not reproduced (no point of a bounded scene gets there).
inline GridCorners grid_corners(uint4 level, float3 point) {
  const float n = (float)level.y;
  const float3 position = clamp(point * n - 0.5f, -1073741824.0f, 1073741824.0f);
  const float3 below = floor(position);
  const float3 up_fraction = position - below;
  const int3 cell0 = convert_int3(below);
  GridCorners c;
  for (int corner = 0; corner < 8; ++corner) {
    // x is the corner's high bit, z its low bit: the official corner order.
    const int3 up = (int3)((corner >> 2) & 1, (corner >> 1) & 1, corner & 1);
    const int3 cell = cell0 + up;
    const float3 w = select(1.0f - up_fraction, up_fraction, up != 0);
    c.weight[corner] = w.x * w.y * w.z;
    if (level.w != 0u) {
      const uint hash = (uint)cell.x ^ ((uint)cell.y * 19349663u) ^ ((uint)cell.z * 83492791u);
      // mod T; a power-of-two T (every table the model builds) takes a mask instead of the division, same value.
      const uint slot = (level.z & (level.z - 1u)) == 0u ? hash & (level.z - 1u) : hash % level.z;
      c.entry[corner] = (int)(level.x + slot);
    } else {
      const int size = (int)level.y;
      const bool inside = all(cell >= 0) && all(cell < size);
      c.entry[corner] = inside ? (int)level.x + (cell.x * size + cell.y) * size + cell.z : -1;
    }
  }
  return c;
}

// approx_erf(1 / (√8 · scale · N)), approx_erf(x) = √(1 − exp(−4x²/π)) for x ≥ 0 (official math.approx_erf): 1 for a
// point, → 0 for a footprint of many cells. Written √(−expm1(−4x²/π)): for a footprint of many cells 1 − exp(−y)
// cancels to 0 in float32 (y < 6e-8), expm1 keeps its relative accuracy. scale·N = 0 gives x = ∞ and weight 1.
inline float level_feature_weight(float scale_cells) {
  const float x = 1.0f / (2.8284271247461903f * scale_cells);
  return sqrt(-expm1(-1.2732395447351628f * x * x));
}

// Point p's weight at `level`: its footprint's with GRID_DOWNWEIGHT, else 1 (instant-ngp's plain grid).
inline float point_level_weight(__global const float* scales, uint p, uint4 level) {
#if GRID_DOWNWEIGHT
  return level_feature_weight(scales[p] * (float)level.y);
#else
  return 1.0f;
#endif
}

__kernel void grid_encoding_fwd(__global const uint4* levels, __global const float* coords,
                                __global const float* scales, __global const float* table,
                                __global float* features, const uint n_points, const uint n_levels) {
  const uint item = get_global_id(0);
  if (item >= n_points * n_levels) return;
  const uint p = item / n_levels, l = item % n_levels;
  const uint4 level = levels[l];
  const GridCorners c = grid_corners(level, vload3(p, coords));
  float sum[GRID_FEATURES];
  for (int f = 0; f < GRID_FEATURES; ++f) sum[f] = 0.0f;
  for (int corner = 0; corner < 8; ++corner) {
    if (c.entry[corner] < 0) continue;
    for (int f = 0; f < GRID_FEATURES; ++f) sum[f] += c.weight[corner] * table[c.entry[corner] * GRID_FEATURES + f];
  }
  const float weight = point_level_weight(scales, p, level);
  for (int f = 0; f < GRID_FEATURES; ++f) features[(size_t)item * GRID_FEATURES + f] = weight * sum[f];
}

// Adds `value` to *address atomically (OpenCL 1.2 has no float atomics: a compare-and-swap on the bits, every read
// atomic too). Different points' corners share table entries (neighbouring points, hash collisions), so the order of
// the additions varies from run to run: the sum of n terms differs from any fixed order's by at most about
// n·2⁻²⁴·Σ|terms| (tests/ops/test_grid_encoding.cpp bounds it so).
inline void atomic_add_float(__global float* address, float value) {
  volatile __global uint* bits = (volatile __global uint*)address;
  uint seen = atomic_or(bits, 0u);
  for (;;) {
    const uint next = as_uint(as_float(seen) + value);
    const uint previous = atomic_cmpxchg(bits, seen, next);
    if (previous == seen) break;
    seen = previous;
  }
}

// d_table += the features' gradients spread back onto the corners (the table's entries are the only parameters: the
// points come from the rays, which are not trained).
__kernel void grid_encoding_bwd(__global const uint4* levels, __global const float* coords,
                                __global const float* scales, __global const float* d_features,
                                __global float* d_table, const uint n_points, const uint n_levels) {
  const uint item = get_global_id(0);
  if (item >= n_points * n_levels) return;
  const uint p = item / n_levels, l = item % n_levels;
  const uint4 level = levels[l];
  const GridCorners c = grid_corners(level, vload3(p, coords));
  const float weight = point_level_weight(scales, p, level);
  for (int corner = 0; corner < 8; ++corner) {
    if (c.entry[corner] < 0) continue;
    for (int f = 0; f < GRID_FEATURES; ++f) {
      const float g = weight * c.weight[corner] * d_features[(size_t)item * GRID_FEATURES + f];
      if (g != 0.0f) atomic_add_float(&d_table[c.entry[corner] * GRID_FEATURES + f], g);
    }
  }
}
