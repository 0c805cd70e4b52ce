// CPU reference (double) of Zip-NeRF's grid encoding, the first stage of `--model zipnerf` (issue 46), as the official
// code computes it (github:jonbarron/camp_zipnerf, internal/grid_utils.py, hash_resample.py, resample.py, math.py):
// multi-resolution levels of N³ cells over the unit cube, each a dense grid when N³ fits the hash table and a hashed
// table otherwise, looked up by trilinear interpolation; each level's features scaled by how much of a Gaussian of
// standard deviation `scale` (in the cube's units) falls inside one cell. Coordinates are in cells: x · N for x in
// [0, 1]³. Pinned by tests/official/test_grid_encoding.cpp against the official functions' own outputs.
#pragma once

#include <cstdint>
#include <vector>

namespace mipnerf::ref {

// The levels' sizes N_l: round(geomspace(min, max, L)) with L = round(1 + supersample · log2(max / min)) levels
// (HashEncoding.grid_sizes; supersample 2 gives a √2 ratio between levels). Empty when L is not an integer within
// 1e-4, which the official code refuses.
std::vector<int> grid_level_sizes(int min_grid_size, int max_grid_size, double scale_supersample);

// The hash table slot of integer cell (x, y, z): (x ⊕ y·19349663 ⊕ z·83492791) mod table_size, in uint32 arithmetic
// (negative cells wrap to uint32, the products wrap modulo 2³²), as hash_resample_3d computes it.
uint32_t hash_slot(int64_t x, int64_t y, int64_t z, uint32_t table_size);

// A hashed level at `cell_coord` (x·N): the 8 corners around cell_coord − 0.5 (cell centres at half-integers),
// weighted trilinearly. `table` is [table_size][features].
std::vector<double> trilerp_hashed(const std::vector<double>& table, uint32_t table_size, int features,
                                   const double cell_coord[3]);

// A dense level of N³ cells at `cell_coord` (x·N): `grid` is [N][N][N][features], indexed [x][y][z]; cell centres
// at half-integers and zero outside the grid, so a point within half a cell of the border blends towards 0
// (resample_3d's CONSTANT_OUTSIDE, as grid_utils.trilerp calls it).
std::vector<double> trilerp_dense(const std::vector<double>& grid, int grid_size, int features,
                                  const double cell_coord[3]);

// The 8 corners around `cell_coord` (x·N) at a level {first entry, N, T, hashed}: their table entries (−1 outside a
// dense grid) and trilinear weights, in the official order (x the corner index's high bit), as the kernel's
// grid_corners.
void level_corners(const uint32_t* level, const double cell_coord[3], int64_t entry[8], double weight[8]);

// The weight of a level's features for a Gaussian whose standard deviation is `scale_cells` cells (scale · N):
// approx_erf(1 / (√8 · scale_cells)), approx_erf(x) = sign(x)·√(1 − exp(−4x²/π)) (math.approx_erf, within 0.007 of
// erf): the fraction of the Gaussian inside one cell, so a footprint wider than a cell sees the cell's features
// faded out, as IPE fades the frequencies a frustum is wider than.
double level_feature_weight(double scale_cells);

// kernels/grid_encoding.cl's two kernels, same names and layouts: `levels` [L][4] (first entry, N, T, hashed), coords
// [P][3] in the unit cube, scales [P] (with downweight), table [entries][features] → features [P][L][features]; the
// backward adds the table's gradient to d_table (in a fixed order, in double).
void grid_encoding_fwd(const std::vector<uint32_t>& levels, const std::vector<double>& coords,
                       const std::vector<double>& scales, const std::vector<double>& table, int features,
                       bool downweight, std::vector<double>& out);
void grid_encoding_bwd(const std::vector<uint32_t>& levels, const std::vector<double>& coords,
                       const std::vector<double>& scales, const std::vector<double>& d_features, int features,
                       bool downweight, std::vector<double>& d_table);

}  // namespace mipnerf::ref
