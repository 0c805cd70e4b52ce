// Zip-NeRF's grid encoding (kernels/grid_encoding.cl) against the double reference (host/ref/grid_encoding.hpp,
// itself pinned to the official code by tests/official/test_grid_encoding.cpp): dense and hashed levels, points on
// cell boundaries and outside the cube, footprints from a point to many cells; the backward's atomic scatter within
// its order bound, and the reference backward against finite differences.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "kernel_checks.hpp"
#include "ops/grid_encoding.hpp"
#include "ref/grid_encoding.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;
using test::kUnitRoundoff;

namespace {

constexpr int kFeatures = 2;
constexpr uint32_t kHashTable = 128;

// Levels of 4 (dense, 64 cells), 7, 16 and 23 cells a side (hashed into 128 entries: collisions by the hundred).
std::vector<ops::GridLevelLayout> test_levels() { return ops::grid_level_layout({4, 7, 16, 23}, kHashTable); }

std::vector<uint32_t> flat_levels(const std::vector<ops::GridLevelLayout>& levels) {
  std::vector<uint32_t> out;
  for (const auto& l : levels) out.insert(out.end(), {l.first_entry, l.grid_size, l.table_size, l.hashed});
  return out;
}

struct Points {
  std::vector<float> coords, scales;
};

// Random points in the cube, points on cell boundaries and centres of every level, points outside it; footprints
// from 0 (a point) over a cell to many cells.
Points test_points(std::mt19937& rng) {
  Points p;
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (int i = 0; i < 200; ++i) {
    for (int a = 0; a < 3; ++a) p.coords.push_back(unit(rng));
    p.scales.push_back(static_cast<float>(test::log_uniform(rng, 1e-5, 1.0)));
  }
  for (float boundary : {0.0f, 0.25f, 0.5f, 1.0f / 7, 3.0f / 16, 1.0f / 23, 1.0f, 0.125f, -0.1f, 1.2f, -3.0f}) {
    p.coords.insert(p.coords.end(), {boundary, unit(rng), boundary});
    p.scales.push_back(0.01f);
  }
  for (float scale : {0.0f, 1e-30f, 1e-3f, 0.1f, 10.0f, 1e30f}) {
    p.coords.insert(p.coords.end(), {unit(rng), unit(rng), unit(rng)});
    p.scales.push_back(scale);
  }
  return p;
}

struct DeviceRun {
  std::vector<float> features, d_table;
};

DeviceRun run_device(bool downweight, const std::vector<ops::GridLevelLayout>& levels, const Points& points,
                     const std::vector<float>& table, const std::vector<float>& d_features) {
  auto& ctx = test::test_context();
  ops::GridEncoding stage(ctx, {kFeatures, downweight});
  const size_t n_points = points.scales.size(), n_levels = levels.size();
  auto levels_dev = test::upload(ctx, flat_levels(levels), "levels");
  auto coords_dev = test::upload(ctx, points.coords, "coords");
  auto scales_dev = test::upload(ctx, points.scales, "scales");
  auto table_dev = test::upload(ctx, table, "table");
  auto d_features_dev = test::upload(ctx, d_features, "d_features");
  ocl::DeviceArray<float> features(ctx, n_points * n_levels * kFeatures, "features");
  auto d_table = test::filled(ctx, table.size(), 0.0f, "d_table");
  const ops::GridEncodingInputs in{levels_dev, coords_dev, scales_dev, n_points, n_levels};
  stage.fwd(in, table_dev, features);
  stage.bwd(in, d_features_dev, d_table);
  return {features.download(ctx), d_table.download(ctx)};
}

std::vector<float> uniform_values(std::mt19937& rng, size_t n) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<float> v(n);
  for (auto& x : v) x = u(rng);
  return v;
}

}  // namespace

TEST_CASE("grid encoding: the level layout is dense while N^3 fits the hash table, hashed beyond") {
  const auto levels = test_levels();
  REQUIRE(levels.size() == 4);
  CHECK(levels[0].hashed == 0);
  CHECK(levels[0].table_size == 64);
  CHECK(levels[1].hashed == 1);
  CHECK(levels[1].first_entry == 64);
  CHECK(levels[3].first_entry == 64 + 2 * kHashTable);
  CHECK(ops::grid_table_entries(levels) == 64 + 3 * kHashTable);
}

// x·N − 0.5 rounds once in float32 (|x·N| ulp), which moves a corner weight by up to about that much on each axis:
// the bound is 3 such moves on each of 8 corners times the largest table value, plus the sum's own rounding, scaled by
// the level weight (itself within a few ulp).
TEST_CASE("grid encoding: forward and backward equal the double reference, with and without the downweighting") {
  std::mt19937 rng(46);
  const auto levels = test_levels();
  const Points points = test_points(rng);
  const std::vector<float> table = uniform_values(rng, ops::grid_table_entries(levels) * kFeatures);
  const size_t n_points = points.scales.size(), n_levels = levels.size();
  const std::vector<float> d_features = uniform_values(rng, n_points * n_levels * kFeatures);
  for (bool downweight : {true, false}) {
    CAPTURE(downweight);
    const DeviceRun device = run_device(downweight, levels, points, table, d_features);
    std::vector<double> expected, expected_d_table(table.size(), 0.0), abs_d_table(table.size(), 0.0);
    std::vector<double> count(table.size(), 0.0);
    const auto levels_flat = flat_levels(levels);
    ref::grid_encoding_fwd(levels_flat, test::to_double(points.coords), test::to_double(points.scales),
                           test::to_double(table), kFeatures, downweight, expected);
    ref::grid_encoding_bwd(levels_flat, test::to_double(points.coords), test::to_double(points.scales),
                           test::to_double(d_features), kFeatures, downweight, expected_d_table);
    // |terms| and their number per entry, for the scatter's order bound: the same backward on |d_features| and 1s.
    std::vector<double> abs_d_features(d_features.size()), ones(d_features.size(), 1.0);
    for (size_t i = 0; i < d_features.size(); ++i) abs_d_features[i] = std::abs(d_features[i]);
    ref::grid_encoding_bwd(levels_flat, test::to_double(points.coords), test::to_double(points.scales),
                           abs_d_features, kFeatures, false, abs_d_table);
    ref::grid_encoding_bwd(levels_flat, test::to_double(points.coords), test::to_double(points.scales), ones,
                           kFeatures, false, count);
    REQUIRE(test::all_finite(device.features));
    REQUIRE(test::all_finite(device.d_table));
    double worst_forward = 0, worst_backward = 0;
    for (size_t p = 0; p < n_points; ++p) {
      for (size_t l = 0; l < n_levels; ++l) {
        const double largest_coord = std::max({std::abs(points.coords[3 * p]), std::abs(points.coords[3 * p + 1]),
                                               std::abs(points.coords[3 * p + 2])});
        const double cells = largest_coord * levels[l].grid_size + 1.0;
        const double position_error = 2 * cells * kUnitRoundoff;  // x·N and the − 0.5, in cells
        const double bound = (8 * 3 * position_error + 16 * kUnitRoundoff) * 1.0 + 1e-7;  // |table| ≤ 1
        for (int f = 0; f < kFeatures; ++f) {
          const size_t i = (p * n_levels + l) * kFeatures + f;
          const double error = std::abs(device.features[i] - expected[i]);
          worst_forward = std::max(worst_forward, error / bound);
        }
      }
    }
    for (size_t e = 0; e < table.size(); ++e) {
      // Each of the `count` additions rounds once (≤ u·|partial sum| ≤ u·Σ|terms|), and each term carries its
      // weights' float32 error (the forward's bound, relative: a few hundred u at 23 cells).
      const double bound = (count[e] + 1) * kUnitRoundoff * abs_d_table[e] + 2e-4 * abs_d_table[e] + 1e-7;
      worst_backward = std::max(worst_backward, std::abs(device.d_table[e] - expected_d_table[e]) / bound);
    }
    INFO("worst forward error / bound " << worst_forward << ", backward " << worst_backward);
    CHECK(worst_forward <= 1.0);
    CHECK(worst_backward <= 1.0);
  }
}

// The forward is linear in the table, so its gradient is exact in double: a central difference of
// Σ d_features·features per table entry equals the reference backward to roundoff.
TEST_CASE("grid encoding: the reference backward is the forward's gradient (finite differences)") {
  std::mt19937 rng(47);
  const auto levels_flat = flat_levels(test_levels());
  Points points = test_points(rng);
  points.coords.resize(3 * 40);
  points.scales.resize(40);
  std::vector<double> table = test::to_double(uniform_values(rng, ops::grid_table_entries(test_levels()) * kFeatures));
  const std::vector<double> d_features =
      test::to_double(uniform_values(rng, points.scales.size() * (levels_flat.size() / 4) * kFeatures));
  std::vector<double> d_table(table.size(), 0.0);
  const auto coords = test::to_double(points.coords), scales = test::to_double(points.scales);
  ref::grid_encoding_bwd(levels_flat, coords, scales, d_features, kFeatures, true, d_table);
  const auto check = test::central_differences(table, d_table, [&](const std::vector<double>& t) {
    std::vector<double> out;
    ref::grid_encoding_fwd(levels_flat, coords, scales, t, kFeatures, true, out);
    return test::weighted_sum(d_features, out);
  }, 1);
  INFO("worst difference " << check.worst << " of gradients up to " << check.largest_gradient);
  CHECK(check.largest_gradient > 0.1);  // the check sees real gradients
  CHECK(check.worst < 1e-9);
}
