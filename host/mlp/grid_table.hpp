// Zip-NeRF's multi-resolution grid as trainable parameters, as a Network holds an MLP's (Barron et al. 2023;
// camp_zipnerf grid_utils.HashEncoding): every level's table in one flat buffer on the device, its gradient beside
// it, the level layout the kernels read. What Adam updates and a checkpoint stores, like Network::params().
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "ops/grid_encoding.hpp"

namespace mipnerf::mlp {

// camp_zipnerf's HashEncoding settings (its names in brackets) as configs/zipnerf/360.gin sets them for the NeRF
// level: 10 levels of 16 … 8192 cells a side, 2^21 entries a hashed level, 4 features.
struct GridConfig {
  int min_grid_size = 16;             // [min_grid_size] N_min
  int max_grid_size = 8192;           // [max_grid_size] N_max
  double scale_supersample = 1.0;     // [scale_supersample] levels = round(1 + s · log2(N_max / N_min))
  uint32_t hash_table_size = 1u << 21;  // [hash_map_size] T
  int features = 4;                   // [num_features] per level
  float init_range = 1e-4f;           // [hash_init_range]; values start U(±init_range / precondition)
  float precondition = 10.0f;         // [precondition_scaling]
  uint64_t seed = 0;

  // Throws mipnerf::Error naming the setting when the sizes do not give a whole number of levels (the official
  // refusal) or a value is out of range.
  void validate() const;
};

// round(geomspace(N_min, N_max, L)) (HashEncoding.grid_sizes); throws as validate().
std::vector<int> grid_level_sizes(const GridConfig& config);

// U(−r, r) per value, r = init_range / precondition, a pure function of config.seed (Philox4x32-10 on the host).
std::vector<float> grid_uniform_init(const GridConfig& config, size_t values);

// "10 levels 16…8192, 2^21 hashed, 4 features: 12.3M params".
std::string describe(const GridConfig& config);

class GridTable {
 public:
  GridTable(ocl::Context& ctx, const GridConfig& config);
  GridTable(const GridTable&) = delete;
  GridTable& operator=(const GridTable&) = delete;

  // Device bytes a table of `config` takes: levels, parameters and gradients.
  static size_t bytes_for(const GridConfig& config);

  const GridConfig& config() const { return config_; }
  const std::vector<ops::GridLevelLayout>& layout() const { return layout_; }
  const ocl::DeviceArray<uint32_t>& levels() const { return levels_; }  // [L][4]
  size_t parameter_count() const { return params_.size(); }

  ocl::DeviceArray<float>& params() { return params_; }  // [entries][features]
  const ocl::DeviceArray<float>& params() const { return params_; }
  ocl::DeviceArray<float>& grads() { return grads_; }
  const ocl::DeviceArray<float>& grads() const { return grads_; }
  std::vector<float> download_params() const;
  void upload_params(const std::vector<float>& values);  // size must be parameter_count()
  std::vector<float> download_grads() const;
  void zero_grad();

 private:
  ocl::Context* ctx_;
  GridConfig config_;
  std::vector<ops::GridLevelLayout> layout_;
  ocl::DeviceArray<uint32_t> levels_;
  ocl::DeviceArray<float> params_;
  ocl::DeviceArray<float> grads_;
};

// Raw pointers to a list of tables, as the graph and the renderer take them.
std::vector<GridTable*> grid_pointers(const std::vector<std::unique_ptr<GridTable>>& grids);

}  // namespace mipnerf::mlp
