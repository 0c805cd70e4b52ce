// Host wrapper of kernels/grid_encoding.cl.
#include "ops/grid_encoding.hpp"

#include "cl/launch.hpp"
#include "core/error.hpp"
#include "ops/stage_checks.hpp"

namespace mipnerf::ops {

std::vector<GridLevelLayout> grid_level_layout(const std::vector<int>& grid_sizes, uint32_t hash_table_size) {
  std::vector<GridLevelLayout> levels;
  uint64_t next_entry = 0;
  for (int size : grid_sizes) {
    if (size < 1) throw Error("grid encoding: a level of " + std::to_string(size) + " cells a side");
    const uint64_t cells = uint64_t(size) * size * size;
    GridLevelLayout level;
    level.first_entry = static_cast<uint32_t>(next_entry);
    level.grid_size = static_cast<uint32_t>(size);
    level.hashed = cells > hash_table_size ? 1 : 0;
    level.table_size = level.hashed ? hash_table_size : static_cast<uint32_t>(cells);
    next_entry += level.table_size;
    if (next_entry >= (uint64_t{1} << 31)) {
      throw Error("grid encoding: the levels' tables hold " + std::to_string(next_entry) +
                  " entries or more; the kernel indexes entries with 32-bit ints: use a smaller hash table");
    }
    levels.push_back(level);
  }
  return levels;
}

size_t grid_table_entries(const std::vector<GridLevelLayout>& levels) {
  return levels.empty() ? 0 : size_t(levels.back().first_entry) + levels.back().table_size;
}

ocl::BuildOptions grid_encoding_build_options(const GridEncodingOptions& options) {
  return ocl::BuildOptions()
      .define("GRID_FEATURES", options.features)
      .define("GRID_DOWNWEIGHT", options.downweight ? 1 : 0);
}

GridEncoding::GridEncoding(ocl::Context& ctx, const GridEncodingOptions& options) : ctx_(&ctx), options_(options) {
  if (options_.features < 1 || options_.features > 16) {
    throw Error("grid encoding: " + std::to_string(options_.features) + " features per level (1 to 16)");
  }
  auto& program = ctx.program({"common.cl", "grid_encoding.cl"}, grid_encoding_build_options(options_));
  fwd_ = &program.kernel("grid_encoding_fwd");
  bwd_ = &program.kernel("grid_encoding_bwd");
}

void GridEncoding::check(const GridEncodingInputs& in, const std::string& where) const {
  detail::require(in.levels, 4 * in.n_levels, where);
  detail::require(in.coords, 3 * in.n_points, where);
  if (options_.downweight) detail::require(in.scales, in.n_points, where);
  detail::to_uint(in.n_points * in.n_levels, where, "point levels");
}

void GridEncoding::fwd(const GridEncodingInputs& in, const ocl::DeviceArray<float>& table,
                       ocl::DeviceArray<float>& features) {
  const std::string where = "grid_encoding_fwd";
  check(in, where);
  detail::require(features, in.n_points * in.n_levels * options_.features, where);
  ocl::set_args(*fwd_, where, in.levels, in.coords, in.scales, table, features,
                detail::to_uint(in.n_points, where, "points"), detail::to_uint(in.n_levels, where, "levels"));
  ocl::launch_1d(*ctx_, *fwd_, in.n_points * in.n_levels, where);
}

void GridEncoding::bwd(const GridEncodingInputs& in, const ocl::DeviceArray<float>& d_features,
                       ocl::DeviceArray<float>& d_table) {
  const std::string where = "grid_encoding_bwd";
  check(in, where);
  detail::require(d_features, in.n_points * in.n_levels * options_.features, where);
  ocl::set_args(*bwd_, where, in.levels, in.coords, in.scales, d_features, d_table,
                detail::to_uint(in.n_points, where, "points"), detail::to_uint(in.n_levels, where, "levels"));
  ocl::launch_1d(*ctx_, *bwd_, in.n_points * in.n_levels, where);
}

}  // namespace mipnerf::ops
