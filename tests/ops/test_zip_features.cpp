// Zip-NeRF's interval features (kernels/zip_features.cl with multisample.cl) against the double reference
// (host/ref/zip_features.hpp, built on the multisample and grid references that tests/official pins to camp_zipnerf):
// the deterministic and the randomized patterns, cones and cylinders, footprints from a point to far wider than the
// cube, zero-width intervals, points outside the cube; the backward's scatter within its order bound; the per-level
// scale and the weight decay; the reference backward against finite differences.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "kernel_checks.hpp"
#include "ops/zip_features.hpp"
#include "ref/grid_encoding.hpp"
#include "ref/multisample.hpp"
#include "ref/zip_features.hpp"
#include "support/test_context.hpp"
#include "support/zip_fixtures.hpp"

using namespace mipnerf;
using test::kUnitRoundoff;

namespace {

constexpr int kZipFeatures = 2;
constexpr uint32_t kZipHashTable = 256;

// 5 dense cells a side, then 9 and 20 hashed into 256 entries (collisions by the hundred).
std::vector<ops::GridLevelLayout> zip_test_levels() { return ops::grid_level_layout({5, 9, 20}, kZipHashTable); }

std::vector<uint32_t> zip_flat_levels(const std::vector<ops::GridLevelLayout>& levels) {
  std::vector<uint32_t> out;
  for (const auto& l : levels) out.insert(out.end(), {l.first_entry, l.grid_size, l.table_size, l.hashed});
  return out;
}

// Rays from around (0, 0, 4) towards the cube [−1.5, 1.5]³ with intervals in t ∈ [1, 7] (some outside the cube), radii
// from 0 (a line) over a pixel's to wider than the cube; some zero-width intervals.
struct ZipTestRays {
  std::vector<float> origins, directions, radii, t_edges;
  size_t n_rays = 0, n_intervals = 5;
};

ZipTestRays zip_test_rays(std::mt19937& rng) {
  ZipTestRays r;
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const float radii[] = {0.0f, 1e-6f, 1e-3f, 2e-3f, 0.05f, 0.5f, 5.0f, 1e3f};
  for (float radius : radii) {
    for (int copy = 0; copy < 6; ++copy) {
      r.origins.insert(r.origins.end(), {unit(rng) - 0.5f, unit(rng) - 0.5f, 4.0f});
      const float dz = copy == 5 ? -1.0f : -(0.8f + 0.4f * unit(rng));
      // copy 5 looks straight down −z: its perpendicular basis takes the (1, 1, 1) branch.
      r.directions.insert(r.directions.end(), {copy == 5 ? 0.0f : 0.3f * (unit(rng) - 0.5f),
                                               copy == 5 ? 0.0f : 0.3f * (unit(rng) - 0.5f), dz});
      r.radii.push_back(radius);
      float t = 1.0f + unit(rng);
      r.t_edges.push_back(t);
      for (size_t i = 0; i < r.n_intervals; ++i) {
        if (!(copy == 2 && i == 1)) t += 0.02f + 1.2f * unit(rng);  // copy 2: one zero-width interval
        r.t_edges.push_back(t);
      }
    }
  }
  r.n_rays = r.radii.size();
  return r;
}

ref::ZipRays to_ref(const ZipTestRays& r) {
  return {test::to_double(r.origins), test::to_double(r.directions), test::to_double(r.radii),
          test::to_double(r.t_edges), r.n_rays, r.n_intervals};
}

ops::ZipFeatureOptions zip_options(bool randomized, bool cylinder, bool downweight,
                                   ops::ZipFeatureOptions::Scatter scatter = ops::ZipFeatureOptions::Scatter::atomic) {
  ops::ZipFeatureOptions o;
  o.scatter = scatter;
  o.features = kZipFeatures;
  o.randomized = randomized;
  o.cylinder = cylinder;
  o.downweight = downweight;
  o.box_min[0] = o.box_min[1] = o.box_min[2] = -1.5f;
  o.box_size = 3.0f;
  return o;
}

ref::ZipFeatureSettings ref_settings(const ops::ZipFeatureOptions& o, RngKey key) {
  return test::zip_reference_settings(o, key);
}

std::vector<float> zip_uniform(std::mt19937& rng, size_t n, float range) {
  std::uniform_real_distribution<float> u(-range, range);
  std::vector<float> v(n);
  for (auto& x : v) x = u(rng);
  return v;
}

struct ZipDeviceRun {
  std::vector<float> features, d_table, level_scale;
};

ZipDeviceRun run_zip_device(const ops::ZipFeatureOptions& options, const ZipTestRays& r, const std::vector<float>& table,
                            const std::vector<float>& d_features, RngKey key) {
  auto& ctx = test::test_context();
  ops::ZipFeatures stage(ctx, options);
  const auto layout = zip_test_levels();
  auto levels = test::upload(ctx, zip_flat_levels(layout), "levels");
  ops::RayBundle rays(ctx, r.n_rays);
  rays.origins.upload(ctx, r.origins);
  rays.directions.upload(ctx, r.directions);
  rays.radii.upload(ctx, r.radii);
  auto t_edges = test::upload(ctx, r.t_edges, "t_edges");
  auto table_dev = test::upload(ctx, table, "table");
  auto d_features_dev = test::upload(ctx, d_features, "d_features");
  const size_t samples = r.n_rays * r.n_intervals;
  auto features = test::filled(ctx, samples * layout.size() * options.level_width(), 7.0f, "features");
  auto d_table = test::filled(ctx, table.size(), 0.0f, "d_table");
  ocl::DeviceArray<float> level_scale(ctx, layout.size(), "level_scale");
  const ops::ZipFeatureInputs in{rays, t_edges, r.n_rays, r.n_intervals};
  const ops::ZipGrid grid{levels, layout};
  stage.level_scale(grid, table_dev, level_scale);
  stage.fwd(in, grid, table_dev, level_scale, features, key);
  stage.bwd(in, grid, d_features_dev, d_table, key);
  return {features.download(ctx), d_table.download(ctx), level_scale.download(ctx)};
}

// With contraction (ZIP_CONTRACT), per ray: the largest Lipschitz constant of contract() over its points, (2r − 1)/r²
// at the nearest point outside the unit ball (1 inside): what a world position error becomes in the contracted
// cube. Empty without contraction.
std::vector<double> zip_contract_factors(const ZipTestRays& r, const ref::ZipFeatureSettings& s) {
  if (!s.contract) return {};
  ref::ZipFeatureSettings world = s;
  world.contract = false;
  std::vector<double> points, scales, factors(r.n_rays, 0.0);
  ref::zip_multisamples(to_ref(r), world, points, scales);
  const size_t per_ray = r.n_intervals * ref::zip_points_per_interval(s);
  for (size_t p = 0; p < scales.size(); ++p) {
    double x[3], norm_sq = 0;
    for (int a = 0; a < 3; ++a) {
      x[a] = points[3 * p + a] * s.box[3] + s.box[a];
      norm_sq += x[a] * x[a];
    }
    const double radius = std::sqrt(norm_sq);
    const double factor = radius <= 1.0 ? 1.0 : (2 * radius - 1) / (radius * radius);
    factors[p / per_ray] = std::max(factors[p / per_ray], factor);
  }
  return factors;
}

// Each multisample's position error in cells at `level` (the forward's budget below). With contraction the world
// error times the ray's factor (zip_contract_factors), plus the contraction's own roundings (a few dozen of |x'| ≤ 2).
double zip_position_error_cells(const ZipTestRays& r, size_t ray, bool cylinder, uint32_t grid_size, float box_size,
                                const std::vector<double>& contract_factors = {}) {
  const double t_max = std::abs(r.t_edges[(ray + 1) * (r.n_intervals + 1) - 1]);
  const double magnitude = 4.0 + t_max * 1.5 + std::sqrt(0.5) * r.radii[ray] * (cylinder ? 1.0 : t_max);
  if (!contract_factors.empty()) {
    return (64 * kUnitRoundoff * magnitude * contract_factors[ray] + 64 * kUnitRoundoff * 2.0) * grid_size / box_size;
  }
  return 64 * kUnitRoundoff * magnitude * grid_size / box_size;
}

// Per table entry, what the float32 positions can move its gradient by: Σ over the terms reaching it of
// |d| · mean · level weight · 3 · position error (a corner weight's error, one per axis), with the reference's corners.
std::vector<double> zip_backward_position_budget(const ZipTestRays& r, const std::vector<uint32_t>& levels,
                                                 const std::vector<float>& d_features,
                                                 const ref::ZipFeatureSettings& s, size_t table_size) {
  std::vector<double> points, scales, budget(table_size, 0.0);
  ref::zip_multisamples(to_ref(r), s, points, scales);
  const std::vector<double> contract_factors = zip_contract_factors(r, s);
  const size_t n_levels = levels.size() / 4, width = s.features + (s.append_scale ? 1 : 0);
  const size_t per_interval = ref::zip_points_per_interval(s);
  const double mean = s.precondition / per_interval;
  for (size_t p = 0; p < scales.size(); ++p) {
    const size_t sample = p / per_interval, ray = sample / r.n_intervals;
    for (size_t l = 0; l < n_levels; ++l) {
      const uint32_t* level = &levels[4 * l];
      const double cell_coord[3] = {points[3 * p] * level[1], points[3 * p + 1] * level[1], points[3 * p + 2] * level[1]};
      int64_t entry[8];
      double weight[8];
      ref::level_corners(level, cell_coord, entry, weight);
      const double level_weight = s.downweight ? ref::level_feature_weight(scales[p] * level[1]) : 1.0;
      const double error =
          3 * zip_position_error_cells(r, ray, s.cylinder, level[1], static_cast<float>(s.box[3]), contract_factors);
      for (int corner = 0; corner < 8; ++corner) {
        if (entry[corner] < 0) continue;
        for (int f = 0; f < s.features; ++f) {
          budget[size_t(entry[corner]) * s.features + f] +=
              std::abs(d_features[(sample * n_levels + l) * width + f]) * mean * level_weight * error;
        }
      }
    }
  }
  return budget;
}

// Error budget of one feature: each multisample's point carries float32 roundings of o + a·ρcosθ + b·ρsinθ + d·t (t
// from a dozen operations on values up to |t| ≈ 10; the angle up to 2π + π/6 before cos/sin): about 64 u of the
// largest term's magnitude, which moves a corner weight by that times N / box_size on each of 3 axes; with |table| ≤ 1
// and the level weight's own few-ulp error, times precondition (10) over the 6 averaged. The scale feature's error is
// the weight's (a few ulp, plus its footprint's) times level_scale.
// One configuration against the reference (the bounds above).
void check_zip_against_reference(const ops::ZipFeatureOptions& options, const ZipTestRays& r,
                                 const std::vector<float>& table, std::mt19937& rng) {
  const auto layout = zip_test_levels();
  const auto levels_flat = zip_flat_levels(layout);
  const RngKey key{0x5eedULL, 17, 300};
  const size_t width = options.level_width(), samples = r.n_rays * r.n_intervals;
  const std::vector<float> d_features = zip_uniform(rng, samples * layout.size() * width, 1.0f);
  const ZipDeviceRun device = run_zip_device(options, r, table, d_features, key);
  const auto s = ref_settings(options, key);
  const auto ref_rays = to_ref(r);
  const auto table_d = test::to_double(table);
  const auto level_scale = ref::zip_level_scale(levels_flat, table_d, kZipFeatures, options.maxval());
  std::vector<double> expected, expected_d_table(table.size(), 0.0), abs_d_table(table.size(), 0.0);
  std::vector<double> count(table.size(), 0.0);
  ref::zip_features_fwd(ref_rays, levels_flat, table_d, level_scale, s, expected);
  ref::zip_features_bwd(ref_rays, levels_flat, test::to_double(d_features), s, expected_d_table);
  std::vector<double> abs_d(d_features.size()), ones(d_features.size(), 1.0);
  for (size_t i = 0; i < d_features.size(); ++i) abs_d[i] = std::abs(d_features[i]);
  ref::zip_features_bwd(ref_rays, levels_flat, abs_d, s, abs_d_table);
  ref::zip_features_bwd(ref_rays, levels_flat, ones, s, count);
  for (size_t l = 0; l < layout.size(); ++l) {
    CHECK(std::abs(device.level_scale[l] - level_scale[l]) <= 4 * kUnitRoundoff * level_scale[l]);
  }
  REQUIRE(test::all_finite(device.features));
  REQUIRE(test::all_finite(device.d_table));
  const std::vector<double> contract_factors = zip_contract_factors(r, s);
  double worst_forward = 0, worst_backward = 0, largest_feature = 0;
  for (size_t sample = 0; sample < samples; ++sample) {
    const size_t ray = sample / r.n_intervals;
    for (size_t l = 0; l < layout.size(); ++l) {
      const double position_error = zip_position_error_cells(r, ray, options.cylinder, layout[l].grid_size,
                                                             options.box_size, contract_factors);
      for (size_t f = 0; f < width; ++f) {
        const size_t i = (sample * layout.size() + l) * width + f;
        const bool scale_feature = f == size_t(kZipFeatures);
        const double bound = scale_feature ? options.precondition * 64 * kUnitRoundoff * level_scale[l] + 1e-12
                                           : options.precondition * (24 * position_error + 64 * kUnitRoundoff);
        worst_forward = std::max(worst_forward, std::abs(device.features[i] - expected[i]) / bound);
        largest_feature = std::max(largest_feature, std::abs(expected[i]));
      }
    }
  }
  const auto position_budget = zip_backward_position_budget(r, levels_flat, d_features, s, table.size());
  for (size_t e = 0; e < table.size(); ++e) {
    // The scatter's order bound (grid_encoding.cl), each term's weight and level-weight roundings (a few ulp),
    // and what the float32 positions move each corner weight by.
    const double bound = (count[e] + 16) * kUnitRoundoff * abs_d_table[e] + position_budget[e] + 1e-9;
    worst_backward = std::max(worst_backward, std::abs(device.d_table[e] - expected_d_table[e]) / bound);
  }
  INFO("worst forward error / bound " << worst_forward << ", backward " << worst_backward);
  CHECK(largest_feature > 1.0);  // the comparison sees real features
  CHECK(worst_forward <= 1.0);
  CHECK(worst_backward <= 1.0);
}

}  // namespace

// Error budget of one feature: each multisample's point carries float32 roundings of o + a·ρcosθ + b·ρsinθ + d·t (t
// from a dozen operations on values up to |t| ≈ 10; the angle up to 2π + π/6 before cos/sin): about 64 u of the
// largest term's magnitude, which moves a corner weight by that times N / box_size on each of 3 axes; with |table| ≤ 1
// and the level weight's own few-ulp error, times precondition (10) over the 6 averaged. The scale feature's error is
// the weight's (a few ulp, plus its footprint's) times level_scale.
TEST_CASE("zip features: forward and backward equal the double reference (patterns, shapes, downweighting)") {
  std::mt19937 rng(4646);
  const ZipTestRays r = zip_test_rays(rng);
  const std::vector<float> table =
      zip_uniform(rng, ops::grid_table_entries(zip_test_levels()) * kZipFeatures, 1.0f);
  using Scatter = ops::ZipFeatureOptions::Scatter;
  for (bool randomized : {false, true}) {
    for (bool cylinder : {false, true}) {
      for (bool downweight : {true, false}) {
        // Both scatters over the configurations, alternating (each is compared with the same reference).
        const Scatter scatter = (randomized != cylinder) ? Scatter::by_level : Scatter::atomic;
        CAPTURE(randomized);
        CAPTURE(cylinder);
        CAPTURE(downweight);
        CAPTURE(static_cast<int>(scatter));
        check_zip_against_reference(zip_options(randomized, cylinder, downweight, scatter), r, table, rng);
      }
    }
  }
}

// One point per interval at the frustum's mean: without footprint weights and the scale feature the plain grid
// Zip-NeRF is measured against, with them the cheaper anti-aliasing (both scatters; training and rendering look up the
// same single point).
TEST_CASE("zip features: one point at the frustum's mean (plain or footprint-weighted) equals the double reference") {
  std::mt19937 rng(4747);
  const ZipTestRays r = zip_test_rays(rng);
  const std::vector<float> table =
      zip_uniform(rng, ops::grid_table_entries(zip_test_levels()) * kZipFeatures, 1.0f);
  using Scatter = ops::ZipFeatureOptions::Scatter;
  for (bool cylinder : {false, true}) {
    for (bool downweight : {false, true}) {
      CAPTURE(cylinder);
      CAPTURE(downweight);
      auto options = zip_options(true, cylinder, downweight, cylinder ? Scatter::by_level : Scatter::atomic);
      options.multisample = false;
      options.append_scale = downweight;
      check_zip_against_reference(options, r, table, rng);
    }
  }
}

// Unbounded scenes (ZIP_CONTRACT): every point through mip-NeRF 360's contraction into the cube [−2, 2]³, its
// footprint times ∛det J. Rays from around (0, 0, 4) with intervals out to t = 1e6 (points from inside the unit ball
// to |x| ≈ 1e6; radii from a line to 1e3): multisampled and single points, both patterns, both scatters, against the
// reference (which contracts by the official's own formulas, pinned in tests/official). The bounds take the world
// positions' float32 error through the contraction's Lipschitz constant (zip_contract_factors).
TEST_CASE("zip features: contracted points (unbounded scenes) equal the double reference out to t = 1e6") {
  std::mt19937 rng(4848);
  ZipTestRays r = zip_test_rays(rng);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (size_t ray = 0; ray < r.n_rays; ++ray) {
    // Log-spaced edges from t ≈ 0.5 to 1e6, each ray's own.
    const double first = std::log(0.5), last = std::log(1e6);
    for (size_t e = 0; e <= r.n_intervals; ++e) {
      const double frac = (e + 0.3 * unit(rng)) / (r.n_intervals + 0.3);
      r.t_edges[ray * (r.n_intervals + 1) + e] = static_cast<float>(std::exp(first + frac * (last - first)));
    }
  }
  const std::vector<float> table =
      zip_uniform(rng, ops::grid_table_entries(zip_test_levels()) * kZipFeatures, 1.0f);
  using Scatter = ops::ZipFeatureOptions::Scatter;
  for (bool multisample : {true, false}) {
    for (bool randomized : {false, true}) {
      CAPTURE(multisample);
      CAPTURE(randomized);
      auto options = zip_options(randomized, false, true, randomized ? Scatter::atomic : Scatter::by_level);
      options.multisample = multisample;
      options.contract = true;
      options.box_min[0] = options.box_min[1] = options.box_min[2] = -2.0f;
      options.box_size = 4.0f;
      check_zip_against_reference(options, r, table, rng);
    }
  }
  // Contraction matters here: without it the same rays give other features (most points lie outside the cube).
  auto plain = zip_options(false, false, true);
  plain.box_min[0] = plain.box_min[1] = plain.box_min[2] = -2.0f;
  plain.box_size = 4.0f;
  auto contracted = plain;
  contracted.contract = true;
  const std::vector<float> d_features(r.n_rays * r.n_intervals * zip_test_levels().size() * plain.level_width(), 1.0f);
  CHECK(run_zip_device(plain, r, table, d_features, {}).features !=
        run_zip_device(contracted, r, table, d_features, {}).features);
  // Cylinders (NDC) are bounded already: refused.
  auto cylinder = contracted;
  cylinder.cylinder = true;
  CHECK_THROWS_WITH_AS(ops::ZipFeatures(test::test_context(), cylinder), doctest::Contains("cylinders"), Error);
}

TEST_CASE("zip features: the training pattern is keyed by (seed, step, ray) and rendering's is fixed") {
  std::mt19937 rng(4647);
  const ZipTestRays r = zip_test_rays(rng);
  const auto layout = zip_test_levels();
  const std::vector<float> table = zip_uniform(rng, ops::grid_table_entries(layout) * kZipFeatures, 1.0f);
  const size_t n = r.n_rays * r.n_intervals * layout.size() * (kZipFeatures + 1);
  const std::vector<float> none(n, 0.0f);
  const auto random = zip_options(true, false, true);
  const auto a = run_zip_device(random, r, table, none, {1, 5, 0}).features;
  CHECK(a == run_zip_device(random, r, table, none, {1, 5, 0}).features);
  CHECK(a != run_zip_device(random, r, table, none, {1, 6, 0}).features);
  CHECK(a != run_zip_device(random, r, table, none, {2, 5, 0}).features);
  const auto fixed = zip_options(false, false, true);
  CHECK(run_zip_device(fixed, r, table, none, {1, 5, 0}).features ==
        run_zip_device(fixed, r, table, none, {2, 6, 9}).features);
}

// Any turn and reversal of the hexagon keeps the multisamples' mean on the ray at the same place (Σ cos = Σ sin = 0
// over a hexagon): the random pattern changes where the points sit around the axis, not the frustum they stand for.
// The level-by-level scatter adds in a fixed order: two runs give the same bits.
TEST_CASE("zip features: the level-by-level backward is deterministic") {
  std::mt19937 rng(4650);
  const ZipTestRays r = zip_test_rays(rng);
  const auto layout = zip_test_levels();
  const std::vector<float> table = zip_uniform(rng, ops::grid_table_entries(layout) * kZipFeatures, 1.0f);
  const std::vector<float> d = zip_uniform(rng, r.n_rays * r.n_intervals * layout.size() * (kZipFeatures + 1), 1.0f);
  const auto options = zip_options(true, false, true, ops::ZipFeatureOptions::Scatter::by_level);
  const auto first = run_zip_device(options, r, table, d, {7, 8, 9}).d_table;
  CHECK(first == run_zip_device(options, r, table, d, {7, 8, 9}).d_table);
}

TEST_CASE("zip features: every pattern's multisamples have the frustum's mean") {
  const ref::Vec3d origin{0.1, -0.2, 3.0}, direction{0.2, 0.1, -1.0};
  const auto fixed = ref::hexify_multisamples(origin, direction, 0.01, 2.0, 2.5, 0);
  for (double turn : {0.0, 0.3, 2.0, 6.0}) {
    for (bool reversed : {false, true}) {
      const auto m = ref::hexify_multisamples(origin, direction, 0.01, 2.0, 2.5, reversed, turn, false);
      for (int a = 0; a < 3; ++a) {
        double mean = 0, fixed_mean = 0;
        for (int j = 0; j < 6; ++j) {
          mean += m.points_world[j][a] / 6;
          fixed_mean += fixed.points_world[j][a] / 6;
        }
        CHECK(mean == doctest::Approx(fixed_mean).epsilon(1e-12));
      }
    }
  }
}

// The one point is the multisamples' mean along the ray, with their mean footprint (their offsets 2j/5 − 1 sum to 0), and off it the
// hexagon's centre for cylinders (constant radius); a cone's hexagon is off-centre by its radius' growth along t.
TEST_CASE("zip features: the plain grid's point is the frustum's mean") {
  ref::ZipRays rays{{0.1, -0.2, 3.0}, {0.2, 0.1, -1.0}, {0.01}, {2.0, 2.5}, 1, 1};
  for (bool cylinder : {false, true}) {
    CAPTURE(cylinder);
    ref::ZipFeatureSettings s;
    s.cylinder = cylinder;
    std::vector<double> six, six_scales, one, one_scales;
    ref::zip_multisamples(rays, s, six, six_scales);
    s.multisample = false;
    ref::zip_multisamples(rays, s, one, one_scales);
    REQUIRE(six.size() == 18);
    REQUIRE(one.size() == 3);
    double mean_scale = 0;
    for (double scale : six_scales) mean_scale += scale / 6;
    CHECK(one_scales[0] > 0.0);
    CHECK(one_scales[0] == doctest::Approx(mean_scale).epsilon(1e-12));  // the hexagon's mean footprint
    double along_six = 0, along_one = 0;
    for (int a = 0; a < 3; ++a) {
      double mean = 0;
      for (int j = 0; j < 6; ++j) mean += six[3 * j + a] / 6;
      along_six += mean * rays.directions[a];
      along_one += one[a] * rays.directions[a];
      if (cylinder) CHECK(one[a] == doctest::Approx(mean).epsilon(1e-12));
    }
    CHECK(along_one == doctest::Approx(along_six).epsilon(1e-12));
  }
}

TEST_CASE("zip features: the weight decay adds mult * value / count per level") {
  auto& ctx = test::test_context();
  std::mt19937 rng(4648);
  const auto layout = zip_test_levels();
  const auto levels_flat = zip_flat_levels(layout);
  const std::vector<float> table = zip_uniform(rng, ops::grid_table_entries(layout) * kZipFeatures, 2.0f);
  const std::vector<float> start = zip_uniform(rng, table.size(), 1.0f);
  ops::ZipFeatures stage(ctx, zip_options(false, false, true));
  auto levels = test::upload(ctx, levels_flat, "levels");
  auto table_dev = test::upload(ctx, table, "table");
  auto d_table = test::upload(ctx, start, "d_table");
  stage.weight_decay({levels, layout}, table_dev, d_table, 0.1f);
  std::vector<double> expected = test::to_double(start);
  ref::grid_weight_decay(levels_flat, test::to_double(table), kZipFeatures, 0.1, expected);
  const auto got = d_table.download(ctx);
  double worst = 0;
  for (size_t i = 0; i < got.size(); ++i) {
    worst = std::max(worst, std::abs(got[i] - expected[i]) / (4 * kUnitRoundoff * (std::abs(expected[i]) + 1e-3)));
  }
  CHECK(worst <= 1.0);
}

// The features are linear in the table, so the reference backward is its exact gradient: central differences of
// Σ d_features · features agree to roundoff.
TEST_CASE("zip features: the reference backward is the forward's gradient (finite differences)") {
  std::mt19937 rng(4649);
  ZipTestRays r = zip_test_rays(rng);
  const auto layout = zip_test_levels();
  const auto levels_flat = zip_flat_levels(layout);
  const auto rays = to_ref(r);
  std::vector<double> table = test::to_double(zip_uniform(rng, ops::grid_table_entries(layout) * kZipFeatures, 1.0f));
  auto plain = zip_options(true, false, false);
  plain.multisample = false;
  plain.append_scale = false;
  for (const auto& options : {zip_options(true, false, true), plain}) {
    CAPTURE(options.multisample);
    const auto s = ref_settings(options, {3, 4, 5});
    const std::vector<double> d_features = test::to_double(
        zip_uniform(rng, r.n_rays * r.n_intervals * layout.size() * options.level_width(), 1.0f));
    std::vector<double> d_table(table.size(), 0.0);
    ref::zip_features_bwd(rays, levels_flat, d_features, s, d_table);
    const std::vector<double> level_scale(layout.size(), 0.25);  // a constant of the step (stop-gradient)
    const auto check = test::central_differences(table, d_table, [&](const std::vector<double>& t) {
      std::vector<double> out;
      ref::zip_features_fwd(rays, levels_flat, t, level_scale, s, out);
      return test::weighted_sum(d_features, out);
    }, 3);
    INFO("worst difference " << check.worst << " of gradients up to " << check.largest_gradient);
    CHECK(check.largest_gradient > 0.1);
    CHECK(check.worst < 1e-8);
  }
}
