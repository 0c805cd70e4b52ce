// The grid's parameters on the device (grid_table.hpp).
#include "mlp/grid_table.hpp"

#include <cmath>
#include <sstream>

#include "core/error.hpp"
#include "core/rng.hpp"

namespace mipnerf::mlp {
namespace {

// Philox stream of the grid's initialisation: apart from the kernels' streams and the MLP's.
constexpr uint32_t kGridInitStream = 0x47524944u;  // "GRID"

size_t level_count(const GridConfig& c) {
  return static_cast<size_t>(std::lround(1.0 + c.scale_supersample * std::log2(double(c.max_grid_size) / c.min_grid_size)));
}

}  // namespace

void GridConfig::validate() const {
  if (min_grid_size < 1 || max_grid_size < min_grid_size) {
    throw Error("grid: grid sizes " + std::to_string(min_grid_size) + " to " + std::to_string(max_grid_size) +
                " (need 1 ≤ grid_min ≤ grid_max)");
  }
  if (!(scale_supersample > 0.0)) throw Error("grid: grid_supersample must be positive");
  const double desired = 1.0 + scale_supersample * std::log2(double(max_grid_size) / min_grid_size);
  if (std::abs(desired - std::round(desired)) > 1e-4) {
    throw Error("grid: sizes " + std::to_string(min_grid_size) + " to " + std::to_string(max_grid_size) +
                " with supersample " + std::to_string(scale_supersample) + " give " + std::to_string(desired) +
                " levels, not a whole number (camp_zipnerf refuses it too): make grid_max / grid_min a power of 2^(1/s)");
  }
  if (hash_table_size < 1) throw Error("grid: the hash table needs at least one entry");
  if (features < 1 || features > 16) throw Error("grid: " + std::to_string(features) + " features per level (1 to 16)");
  if (!(init_range > 0.0f) || !(precondition > 0.0f)) throw Error("grid: init range and precondition must be positive");
}

std::vector<int> grid_level_sizes(const GridConfig& c) {
  c.validate();
  const size_t levels = level_count(c);
  std::vector<int> sizes;
  for (size_t l = 0; l < levels; ++l) {
    const double t = levels == 1 ? 0.0 : double(l) / double(levels - 1);
    const double size = l + 1 == levels ? c.max_grid_size : c.min_grid_size * std::pow(double(c.max_grid_size) / c.min_grid_size, t);
    sizes.push_back(static_cast<int>(std::lround(size)));
  }
  return sizes;
}

std::vector<float> grid_uniform_init(const GridConfig& c, size_t values) {
  const double limit = double(c.init_range) / c.precondition;
  std::vector<float> out(values);
  for (size_t i = 0; i < values; i += 4) {
    const auto u = rng_uniform4(c.seed, static_cast<uint32_t>(i / 4), static_cast<uint32_t>(i >> 34), 0, kGridInitStream);
    for (size_t k = 0; k < 4 && i + k < values; ++k) out[i + k] = static_cast<float>((2.0 * u[k] - 1.0) * limit);
  }
  return out;
}

std::string describe(const GridConfig& c) {
  const auto sizes = grid_level_sizes(c);
  const auto layout = ops::grid_level_layout(sizes, c.hash_table_size);
  size_t hashed = 0;
  for (const auto& l : layout) hashed += l.hashed;
  std::ostringstream out;
  out << sizes.size() << " levels " << sizes.front() << "…" << sizes.back() << " (" << hashed << " hashed into 2^"
      << std::log2(double(c.hash_table_size)) << "), " << c.features << " features: "
      << ops::grid_table_entries(layout) * c.features << " params";
  return out.str();
}

GridTable::GridTable(ocl::Context& ctx, const GridConfig& config)
    : ctx_(&ctx), config_(config), layout_(ops::grid_level_layout(grid_level_sizes(config), config.hash_table_size)) {
  std::vector<uint32_t> flat;
  for (const auto& l : layout_) flat.insert(flat.end(), {l.first_entry, l.grid_size, l.table_size, l.hashed});
  levels_ = ocl::DeviceArray<uint32_t>(ctx, flat.size(), "grid levels [L][4]");
  levels_.upload(ctx, flat);
  const size_t values = ops::grid_table_entries(layout_) * size_t(config_.features);
  params_ = ocl::DeviceArray<float>(ctx, values, "grid table [entries][F]");
  grads_ = ocl::DeviceArray<float>(ctx, values, "grid table gradient [entries][F]");
  params_.upload(ctx, grid_uniform_init(config_, values));
  zero_grad();
}

size_t GridTable::bytes_for(const GridConfig& config) {
  const auto layout = ops::grid_level_layout(grid_level_sizes(config), config.hash_table_size);
  return layout.size() * 4 * sizeof(uint32_t) + 2 * ops::grid_table_entries(layout) * config.features * sizeof(float);
}

std::vector<float> GridTable::download_params() const { return params_.download(*ctx_); }

void GridTable::upload_params(const std::vector<float>& values) {
  if (values.size() != params_.size()) {
    throw Error("grid: " + std::to_string(values.size()) + " parameter values given, the grid (" + describe(config_) +
                ") has " + std::to_string(params_.size()));
  }
  params_.upload(*ctx_, values);
}

std::vector<float> GridTable::download_grads() const { return grads_.download(*ctx_); }

void GridTable::zero_grad() { grads_.fill(*ctx_, 0.0f); }

std::vector<GridTable*> grid_pointers(const std::vector<std::unique_ptr<GridTable>>& grids) {
  std::vector<GridTable*> out;
  for (const auto& g : grids) out.push_back(g.get());
  return out;
}

}  // namespace mipnerf::mlp
