// Host wrapper of kernels/zip_features.cl (with multisample.cl and grid_encoding.cl): Zip-NeRF's features of every
// interval of a chunk, from its multisamples looked up in the multi-resolution grid, forward and backward, the
// per-level scale of the appended scale feature, and the grid's weight decay gradient.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "cl/program.hpp"
#include "core/stage_options.hpp"
#include "ops/grid_encoding.hpp"
#include "ops/ray_bundle.hpp"

namespace mipnerf::ops {

// What the stage compiles in and is called with (camp_zipnerf's names in brackets).
struct ZipFeatureOptions {
  int features = 4;           // GRID_FEATURES per level [num_features]
  bool multisample = true;    // ZIP_MULTISAMPLE: the frustum's 6 multisamples (off: one point at its mean)
  bool downweight = true;     // GRID_DOWNWEIGHT: each level faded by the footprint (Zip-NeRF; off: a plain grid)
  bool append_scale = true;   // GRID_APPEND_SCALE: (2w − 1) · level_scale per level [append_scale]
  bool cylinder = false;      // ZIP_CYLINDER: NDC rays' constant footprint
  bool randomized = false;    // ZIP_RANDOMIZED: a random turn and reversal per interval (training)
  // ZIP_CONTRACT: unbounded scenes: each point through mip-NeRF 360's contraction before the cube (then [−2, 2]³), its
  // footprint times ∛det of the contraction's Jacobian [warp_fn = coord.contract, coord.contract3_isoscale]. World
  // rays only (NDC's cylinders are bounded already).
  bool contract = false;
  float box_min[3] = {-1.0f, -1.0f, -1.0f};  // the grid's cube [bbox_scaling]
  float box_size = 2.0f;
  float scale_mult = 0.5f;    // footprint = scale_mult · the multisample's distance from the axis [unscented_scale_mult]
  float precondition = 10.0f;  // features × this [precondition_scaling]
  float init_range = 1e-4f;    // table values start U(−r/precondition, r/precondition) [hash_init_range]
  // How the backward adds onto the table: one work-item per level in a fixed order (deterministic, no atomics: for
  // CPU devices) or one per sample with atomic adds (the parallel scatter a GPU needs; the order varies by run).
  enum class Scatter { by_level, atomic } scatter = Scatter::by_level;

  int level_width() const { return features + (append_scale ? 1 : 0); }
  int points_per_interval() const { return multisample ? 6 : 1; }
  float maxval() const { return init_range / precondition; }
};

ocl::BuildOptions zip_features_build_options(const ZipFeatureOptions& options);

// One chunk's intervals: the rays and their N + 1 edges (as the Gaussian stage reads them).
struct ZipFeatureInputs {
  const RayBundle& rays;
  const ocl::DeviceArray<float>& t_edges;  // [R][N+1]
  size_t n_rays;
  size_t n_intervals;
};

// The grid: its levels on the device and on the host (for checks and the weight decay's sizes).
struct ZipGrid {
  const ocl::DeviceArray<uint32_t>& levels;  // [L][4]
  const std::vector<GridLevelLayout>& layout;
};

class ZipFeatures {
 public:
  ZipFeatures(ocl::Context& ctx, const ZipFeatureOptions& options);
  const ZipFeatureOptions& options() const { return options_; }

  // level_scale [L] from the table (once per step: it is the step's constant).
  void level_scale(const ZipGrid& grid, const ocl::DeviceArray<float>& table, ocl::DeviceArray<float>& level_scale);
  // features [R·N][L][level_width] (`key` draws the patterns when randomized).
  void fwd(const ZipFeatureInputs& in, const ZipGrid& grid, const ocl::DeviceArray<float>& table,
           const ocl::DeviceArray<float>& level_scale, ocl::DeviceArray<float>& features, RngKey key = {});
  // ADDS the table's gradient to d_table (same `key` as the forward), by options().scatter.
  void bwd(const ZipFeatureInputs& in, const ZipGrid& grid, const ocl::DeviceArray<float>& d_features,
           ocl::DeviceArray<float>& d_table, RngKey key = {});
  // d_table += mult · value / count_l (the official param_regularizers' mean-square decay, per level).
  void weight_decay(const ZipGrid& grid, const ocl::DeviceArray<float>& table, ocl::DeviceArray<float>& d_table,
                    float mult);

 private:
  void check(const ZipFeatureInputs& in, const ZipGrid& grid, const std::string& where) const;

  ocl::Context* ctx_;
  ZipFeatureOptions options_;
  ::cl::Kernel* fwd_;
  ::cl::Kernel* bwd_;
  ::cl::Kernel* bwd_by_level_;
  ::cl::Kernel* level_scale_;
  ::cl::Kernel* weight_decay_;
};

}  // namespace mipnerf::ops
