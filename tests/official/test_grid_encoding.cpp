// Zip-NeRF's grid encoding and multisample references (host/ref/grid_encoding.hpp, multisample.hpp) against the
// official camp_zipnerf functions' own outputs (fixtures/zipnerf_grid.json, written by make_grid_vectors.py): level
// sizes, the hashed lookup (the corner hash and trilinear weights, also at cell boundaries, negative cells and cells
// whose hash products wrap), the dense lookup (zero outside the grid), the per-level feature weight and the
// deterministic hexagonal multisamples. The official math ran in float64, so the bound is roundoff.
#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include "official_fixtures.hpp"
#include "ref/grid_encoding.hpp"
#include "ref/multisample.hpp"
#include "ref/zip_features.hpp"

using namespace mipnerf;

namespace {

io::Json grid_fixture() {
  return official::zipnerf_fixture("zipnerf_grid.json");
}

// The largest |ours − official| over a lookup's coordinates (`lookup` gives our features at one coordinate).
template <typename Lookup>
double worst_lookup_error(const io::Json& case_json, int features, Lookup lookup) {
  const auto coords = official::flat(case_json.at("coords"));
  const auto expected = official::flat(case_json.at("values"));
  REQUIRE(expected.size() == coords.size() / 3 * features);
  double worst = 0;
  for (size_t i = 0; i < coords.size() / 3; ++i) {
    const std::vector<double> ours = lookup(&coords[3 * i]);
    for (int f = 0; f < features; ++f) worst = std::max(worst, std::abs(ours[f] - expected[i * features + f]));
  }
  return worst;
}

}  // namespace

TEST_CASE("zipnerf grid: the level sizes are HashEncoding.grid_sizes'") {
  const io::Json fixture = grid_fixture();  // held: a range-for over grid_fixture().at(…) would read a freed temporary
  for (const auto& setting : fixture.at("level_sizes")) {
    const auto sizes = ref::grid_level_sizes(setting.at("min").get<int>(), setting.at("max").get<int>(),
                                             setting.at("supersample").get<double>());
    CHECK(sizes == setting.at("sizes").get<std::vector<int>>());
  }
  CHECK(ref::grid_level_sizes(16, 100, 1.0).empty());  // 1 + log2(6.25) levels: not an integer, refused
  CHECK(ref::grid_level_sizes(16, 512, 0.5).empty());  // 3.5 levels, refused too
  CHECK(fixture.at("level_sizes").size() == 4);        // the loop above compared something
}

TEST_CASE("zipnerf grid: a hashed level's lookup is hash_resample_3d's, also at boundaries and wrapping cells") {
  const io::Json hash = grid_fixture().at("hash");
  const auto table = official::flat(hash.at("table"));
  const uint32_t table_size = static_cast<uint32_t>(hash.at("table").size());
  const double worst = worst_lookup_error(hash, 2, [&](const double* coord) {
    return ref::trilerp_hashed(table, table_size, 2, coord);
  });
  INFO("worst difference " << worst);
  CHECK(worst < 1e-12);
}

TEST_CASE("zipnerf grid: a dense level's lookup is resample_3d's as trilerp calls it, zero outside the grid") {
  const io::Json dense = grid_fixture().at("dense");
  const auto grid = official::flat(dense.at("grid"));
  const int grid_size = static_cast<int>(dense.at("grid").size());
  const double worst = worst_lookup_error(dense, 2, [&](const double* coord) {
    return ref::trilerp_dense(grid, grid_size, 2, coord);
  });
  INFO("worst difference " << worst);
  CHECK(worst < 1e-12);
}

TEST_CASE("zipnerf grid: a level's feature weight is approx_erf(1 / (sqrt(8) scale N)), finite at both extremes") {
  const io::Json weight = grid_fixture().at("weight");
  const auto scales = official::flat(weight.at("scale_cells"));
  const auto expected = official::flat(weight.at("values"));
  for (size_t i = 0; i < scales.size(); ++i) {
    CAPTURE(scales[i]);
    const double ours = ref::level_feature_weight(scales[i]);
    CHECK(std::isfinite(ours));
    CHECK(std::abs(ours - expected[i]) < 1e-12);
  }
  CHECK(ref::level_feature_weight(1e-30) == 1.0);  // a point: the cell's features whole
  CHECK(ref::level_feature_weight(1e30) >= 0.0);   // a footprint of many cells: faded to (nearly) nothing
  CHECK(ref::level_feature_weight(1e30) < 1e-29);
}

TEST_CASE("zipnerf multisamples: the deterministic hexagons are coord.hexify's, also for a ray along +z") {
  const io::Json hex = grid_fixture().at("hexify");
  const auto origins = official::flat(hex.at("origins")), directions = official::flat(hex.at("directions"));
  const auto radii = official::flat(hex.at("radii")), tdist = official::flat(hex.at("tdist"));
  const auto control = official::flat(hex.at("control")), perp_mag = official::flat(hex.at("perp_mag"));
  const size_t rays = origins.size() / 3, edges = tdist.size() / rays, intervals = edges - 1;
  REQUIRE(control.size() == rays * intervals * 6 * 3);
  double worst_point = 0, worst_perp = 0;
  for (size_t r = 0; r < rays; ++r) {
    for (size_t i = 0; i < intervals; ++i) {
      const ref::Multisamples m = ref::hexify_multisamples(
          {origins[3 * r], origins[3 * r + 1], origins[3 * r + 2]},
          {directions[3 * r], directions[3 * r + 1], directions[3 * r + 2]}, radii[r], tdist[r * edges + i],
          tdist[r * edges + i + 1], static_cast<int>(i));
      for (int j = 0; j < 6; ++j) {
        const size_t sample = (r * intervals + i) * 6 + j;
        worst_perp = std::max(worst_perp, std::abs(m.perp_radius[j] - perp_mag[sample]));
        for (int a = 0; a < 3; ++a) {
          worst_point = std::max(worst_point, std::abs(m.points_world[j][a] - control[3 * sample + a]));
        }
      }
    }
  }
  INFO("worst point difference " << worst_point << ", off-axis radius " << worst_perp);
  CHECK(worst_point < 1e-12);
  CHECK(worst_perp < 1e-12);
}

// Unbounded scenes: each multisample through coord.contract and its footprint times coord.contract3_isoscale (models.py
// predict_density with warp_fn = contract), from fixtures/zipnerf_contract.json (make_zip_contract_vectors.py): points
// inside the unit ball, on the sphere and one float32 ulp either side, at the origin, and out to |x| ≈ 2e15. The
// reference writes the official's formulas in double: roundoff agreement. track_isotropic, the general form, agrees
// with the fast one (to its own float64 determinant's digits) wherever its clamp (float32 tiny) is not reached.
TEST_CASE("zipnerf contraction: a multisample's point and footprint scale are coord.contract's and contract3_isoscale's") {
  const io::Json fixture = official::zipnerf_fixture("zipnerf_contract.json");
  const auto points = official::flat(fixture.at("points"));
  const auto contracted = official::flat(fixture.at("contract"));
  const auto isoscale = official::flat(fixture.at("contract3_isoscale"));
  const auto scales = official::flat(fixture.at("scales"));
  const auto tracked = official::flat(fixture.at("track_isotropic_scale"));
  const size_t n = points.size() / 3;
  REQUIRE(n >= 30);
  size_t clamped = 0;
  for (size_t i = 0; i < n; ++i) {
    INFO("point " << i << ": " << points[3 * i] << ", " << points[3 * i + 1] << ", " << points[3 * i + 2]);
    double ours[3];
    ref::zip_contract(&points[3 * i], ours);
    for (int a = 0; a < 3; ++a) CHECK(std::abs(ours[a] - contracted[3 * i + a]) <= 1e-14 * 2.0);
    const double scale = ref::zip_contract_isoscale(&points[3 * i]);
    CHECK(std::abs(scale - isoscale[i]) <= 1e-13 * isoscale[i]);
    // The general form's determinant of J (radial 1/r² against tangential ≈ 2/r) loses digits as r grows: 2e-10
    // relative at |x| = 8e5 in float64.
    if (std::abs(tracked[i] - scales[i] * isoscale[i]) <= 1e-9 * tracked[i]) continue;
    ++clamped;  // the general form's clamp: only far out, where det J < float32 tiny
    CHECK(isoscale[i] * isoscale[i] * isoscale[i] < 1.2e-38);
  }
  CHECK(clamped <= 2);
}
