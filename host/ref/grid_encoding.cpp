// Zip-NeRF's grid lookups and level weights in double precision (the official conventions, grid_encoding.hpp).
#include "ref/grid_encoding.hpp"

#include <cmath>

namespace mipnerf::ref {
namespace {

// The 8 corners of the cell block around `position` (already shifted to corner coordinates) and their trilinear
// weights, in the official order (x slowest, z fastest).
struct Corners {
  int64_t cell[8][3];
  double weight[8];
};

Corners corners_of(const double position[3]) {
  Corners c{};
  const double floor_x[3] = {std::floor(position[0]), std::floor(position[1]), std::floor(position[2])};
  for (int corner = 0; corner < 8; ++corner) {
    double weight = 1.0;
    for (int axis = 0; axis < 3; ++axis) {
      const int up = (corner >> (2 - axis)) & 1;  // x is the corner index's high bit, z its low bit
      const double fraction = position[axis] - floor_x[axis];
      c.cell[corner][axis] = static_cast<int64_t>(floor_x[axis]) + up;
      weight *= up ? fraction : 1.0 - fraction;
    }
    c.weight[corner] = weight;
  }
  return c;
}

}  // namespace

std::vector<int> grid_level_sizes(int min_grid_size, int max_grid_size, double scale_supersample) {
  const double desired = 1.0 + scale_supersample * std::log2(static_cast<double>(max_grid_size) / min_grid_size);
  const double count = std::round(desired);
  if (std::abs(desired - count) > 1e-4 || count < 1) return {};
  std::vector<int> sizes;
  const int levels = static_cast<int>(count);
  for (int l = 0; l < levels; ++l) {
    const double t = levels == 1 ? 0.0 : static_cast<double>(l) / (levels - 1);
    // geomspace: min · (max/min)^t, its ends exact.
    const double size = l == levels - 1 ? max_grid_size : min_grid_size * std::pow(double(max_grid_size) / min_grid_size, t);
    sizes.push_back(static_cast<int>(std::round(size)));
  }
  return sizes;
}

uint32_t hash_slot(int64_t x, int64_t y, int64_t z, uint32_t table_size) {
  const uint32_t ux = static_cast<uint32_t>(x), uy = static_cast<uint32_t>(y), uz = static_cast<uint32_t>(z);
  return (ux ^ (uy * 19349663u) ^ (uz * 83492791u)) % table_size;
}

void level_corners(const uint32_t* level, const double cell_coord[3], int64_t entry[8], double weight[8]) {
  const double position[3] = {cell_coord[0] - 0.5, cell_coord[1] - 0.5, cell_coord[2] - 0.5};
  const Corners c = corners_of(position);
  for (int corner = 0; corner < 8; ++corner) {
    weight[corner] = c.weight[corner];
    const int64_t* cell = c.cell[corner];
    if (level[3]) {
      entry[corner] = int64_t(level[0]) + hash_slot(cell[0], cell[1], cell[2], level[2]);
    } else {
      const int64_t size = level[1];
      const bool inside = cell[0] >= 0 && cell[0] < size && cell[1] >= 0 && cell[1] < size && cell[2] >= 0 &&
                          cell[2] < size;
      entry[corner] = inside ? int64_t(level[0]) + (cell[0] * size + cell[1]) * size + cell[2] : -1;
    }
  }
}

namespace {

// The level's features at `cell_coord`: the corners' entries of `table` weighted and summed.
std::vector<double> level_lookup(const uint32_t* level, const std::vector<double>& table, int features,
                                 const double cell_coord[3]) {
  int64_t entry[8];
  double weight[8];
  level_corners(level, cell_coord, entry, weight);
  std::vector<double> out(features, 0.0);
  for (int corner = 0; corner < 8; ++corner) {
    if (entry[corner] < 0) continue;
    for (int f = 0; f < features; ++f) out[f] += weight[corner] * table[size_t(entry[corner]) * features + f];
  }
  return out;
}

// Point p's cell coordinates at `level` (x·N) and its feature weight there (1 without the downweighting).
double point_at_level(const uint32_t* level, const std::vector<double>& coords, const std::vector<double>& scales,
                      size_t p, bool downweight, double cell_coord[3]) {
  for (int a = 0; a < 3; ++a) cell_coord[a] = coords[3 * p + a] * level[1];
  return downweight ? level_feature_weight(scales[p] * level[1]) : 1.0;
}

}  // namespace

std::vector<double> trilerp_hashed(const std::vector<double>& table, uint32_t table_size, int features,
                                   const double cell_coord[3]) {
  const uint32_t level[4] = {0, 1, table_size, 1};  // the grid size plays no part in a hashed lookup
  return level_lookup(level, table, features, cell_coord);
}

std::vector<double> trilerp_dense(const std::vector<double>& grid, int grid_size, int features,
                                  const double cell_coord[3]) {
  const uint32_t n = static_cast<uint32_t>(grid_size);
  const uint32_t level[4] = {0, n, n * n * n, 0};
  return level_lookup(level, grid, features, cell_coord);
}

double level_feature_weight(double scale_cells) {
  const double x = 1.0 / (std::sqrt(8.0) * scale_cells);
  // √(−expm1(−y)) = √(1 − e^−y) without its cancellation for a footprint of many cells.
  return (x > 0 ? 1.0 : x < 0 ? -1.0 : 0.0) * std::sqrt(-std::expm1(-(4.0 / M_PI) * x * x));
}


void grid_encoding_fwd(const std::vector<uint32_t>& levels, const std::vector<double>& coords,
                       const std::vector<double>& scales, const std::vector<double>& table, int features,
                       bool downweight, std::vector<double>& out) {
  const size_t n_levels = levels.size() / 4, n_points = coords.size() / 3;
  out.assign(n_points * n_levels * features, 0.0);
  for (size_t p = 0; p < n_points; ++p) {
    for (size_t l = 0; l < n_levels; ++l) {
      double cell_coord[3];
      const double level_weight = point_at_level(&levels[4 * l], coords, scales, p, downweight, cell_coord);
      const std::vector<double> f_level = level_lookup(&levels[4 * l], table, features, cell_coord);
      for (int f = 0; f < features; ++f) out[(p * n_levels + l) * features + f] = level_weight * f_level[f];
    }
  }
}

void grid_encoding_bwd(const std::vector<uint32_t>& levels, const std::vector<double>& coords,
                       const std::vector<double>& scales, const std::vector<double>& d_features, int features,
                       bool downweight, std::vector<double>& d_table) {
  const size_t n_levels = levels.size() / 4, n_points = coords.size() / 3;
  for (size_t p = 0; p < n_points; ++p) {
    for (size_t l = 0; l < n_levels; ++l) {
      double cell_coord[3];
      const double level_weight = point_at_level(&levels[4 * l], coords, scales, p, downweight, cell_coord);
      int64_t entry[8];
      double weight[8];
      level_corners(&levels[4 * l], cell_coord, entry, weight);
      for (int corner = 0; corner < 8; ++corner) {
        if (entry[corner] < 0) continue;
        for (int f = 0; f < features; ++f) {
          d_table[size_t(entry[corner]) * features + f] +=
              level_weight * weight[corner] * d_features[(p * n_levels + l) * features + f];
        }
      }
    }
  }
}

}  // namespace mipnerf::ref
