// CPU reference (double) of kernels/zip_features.cl, same names: Zip-NeRF's features of each interval, from its 6
// multisamples (ref/multisample.hpp) looked up in the grid (ref/grid_encoding.hpp), each level downweighted by the
// multisample's footprint, the level's scale feature appended, averaged over the multisamples and multiplied by the
// preconditioning factor (camp_zipnerf models.py predict_density, grid_utils.HashEncoding.__call__).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mipnerf::ref {

// What the stage is compiled and called with, as the kernel takes it.
struct ZipFeatureSettings {
  int features = 4;               // per level (GRID_FEATURES)
  bool multisample = true;        // ZIP_MULTISAMPLE: 6 multisamples, or one point at the frustum's mean
  bool downweight = true;         // GRID_DOWNWEIGHT
  bool append_scale = true;       // GRID_APPEND_SCALE
  bool cylinder = false;          // ZIP_CYLINDER
  bool randomized = false;        // ZIP_RANDOMIZED: patterns from (seed, step, first_ray + ray, interval)
  bool contract = false;          // ZIP_CONTRACT: points through contract(), footprints × zip_contract_isoscale
  double box[4] = {0, 0, 0, 1};   // min corner and size of the grid's cube
  double scale_mult = 0.5;
  double precondition = 10.0;
  uint64_t seed = 0;
  uint32_t step = 0;
  uint32_t first_ray = 0;
};

// The rays (origins, directions [R][3], radii [R]) and each ray's N + 1 interval edges.
struct ZipRays {
  std::vector<double> origins, directions, radii, t_edges;
  size_t n_rays = 0;
  size_t n_intervals = 0;
};

// mip-NeRF 360's contraction of a point (eq. 10) and the cube root of its Jacobian's determinant there, written as the
// official writes them (camp_zipnerf coord.contract: m = max(1, |x|²), x·(2√m − 1)/m; coord.contract3_isoscale:
// exp(⅔ log(2√m − 1) − log m)), in double: the independent form the kernel's is checked against.
void zip_contract(const double x[3], double out[3]);
double zip_contract_isoscale(const double x[3]);

// Points per interval: 6 multisamples, or one at the frustum's mean.
inline int zip_points_per_interval(const ZipFeatureSettings& s) { return s.multisample ? 6 : 1; }

// Each multisample of every interval in the unit cube ([R·N·P][3]) and its footprint there ([R·N·P]), P points per interval.
void zip_multisamples(const ZipRays& rays, const ZipFeatureSettings& s, std::vector<double>& unit_points,
                      std::vector<double>& scales);

// level_scale[l] = √(maxval² + mean of level l's table values²).
std::vector<double> zip_level_scale(const std::vector<uint32_t>& levels, const std::vector<double>& table,
                                    int features, double maxval);

// features [R·N][L][features + append_scale].
void zip_features_fwd(const ZipRays& rays, const std::vector<uint32_t>& levels, const std::vector<double>& table,
                      const std::vector<double>& level_scale, const ZipFeatureSettings& s,
                      std::vector<double>& features);
// d_table += ∂features/∂table · d_features (the scale features carry no table gradient).
void zip_features_bwd(const ZipRays& rays, const std::vector<uint32_t>& levels, const std::vector<double>& d_features,
                      const ZipFeatureSettings& s, std::vector<double>& d_table);

// d_table += mult · value / count_l for each value of level l (the gradient of mult · ½ · mean(table_l²)).
void grid_weight_decay(const std::vector<uint32_t>& levels, const std::vector<double>& table, int features,
                       double mult, std::vector<double>& d_table);

}  // namespace mipnerf::ref
