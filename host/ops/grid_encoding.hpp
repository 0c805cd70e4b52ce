// Host wrapper of kernels/grid_encoding.cl: Zip-NeRF's multi-resolution grid encoding (hashed and dense levels,
// trilinear lookups, each level's features downweighted by the point's footprint), forward and backward.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "cl/program.hpp"

namespace mipnerf::ops {

struct GridEncodingOptions {
  int features = 2;         // per level (camp_zipnerf's num_features)
  bool downweight = true;   // scale each level's features by its footprint weight (Zip-NeRF); false: instant-ngp's
};

// One level as the kernel reads it ([L][4] uint): first table entry, cells a side N, table size T, hashed.
struct GridLevelLayout {
  uint32_t first_entry = 0;
  uint32_t grid_size = 0;
  uint32_t table_size = 0;
  uint32_t hashed = 0;
};

// The levels of `grid_sizes` one after another in one table: a dense N³ grid where N³ ≤ hash_table_size, else a
// hashed table of hash_table_size entries (grid_utils.HashEncoding's rule). Throws mipnerf::Error when the table
// would hold 2^31 entries or more (the kernel indexes entries with int).
std::vector<GridLevelLayout> grid_level_layout(const std::vector<int>& grid_sizes, uint32_t hash_table_size);
// Entries of the whole table (the last level's end).
size_t grid_table_entries(const std::vector<GridLevelLayout>& levels);

ocl::BuildOptions grid_encoding_build_options(const GridEncodingOptions& options);  // GRID_FEATURES, GRID_DOWNWEIGHT

struct GridEncodingInputs {
  const ocl::DeviceArray<uint32_t>& levels;  // [L][4] (GridLevelLayout)
  const ocl::DeviceArray<float>& coords;     // [P][3] in the unit cube
  const ocl::DeviceArray<float>& scales;     // [P] (read only with downweight)
  size_t n_points;
  size_t n_levels;
};

class GridEncoding {
 public:
  GridEncoding(ocl::Context& ctx, const GridEncodingOptions& options);
  const GridEncodingOptions& options() const { return options_; }

  // Enqueues grid_encoding_fwd: features [P][L][F] from `table` [entries][F].
  void fwd(const GridEncodingInputs& in, const ocl::DeviceArray<float>& table, ocl::DeviceArray<float>& features);
  // Enqueues grid_encoding_bwd: ADDS the table's gradient to d_table [entries][F] (zero it first for one batch's).
  // Atomic additions: the order varies between runs, within the bound grid_encoding.cl states.
  void bwd(const GridEncodingInputs& in, const ocl::DeviceArray<float>& d_features, ocl::DeviceArray<float>& d_table);

 private:
  void check(const GridEncodingInputs& in, const std::string& where) const;

  ocl::Context* ctx_;
  GridEncodingOptions options_;
  ::cl::Kernel* fwd_;
  ::cl::Kernel* bwd_;
};

}  // namespace mipnerf::ops
