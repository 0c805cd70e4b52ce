// mip-NeRF 360's encoding of contracted frustums (kernels/contracted_ipe.cl) against the double reference
// (host/ref/contracted_ipe.hpp, which tests/official/test_contracted_ipe.cpp pins to multinerf): random rays through
// and around the unit ball with reciprocal-spaced intervals out to 1e6, and hard cases (intervals out to 1e18, zero-
// width intervals, cones far wider and far thinner than a pixel's, an axis-aligned direction, intervals straddling the
// unit sphere), every feature within the derived float32 bound and finite; the bound itself tight enough that the
// basis' order or one degree's scale changed fails it; bad degrees refused.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/error.hpp"
#include "core/geodesic_basis.hpp"
#include "kernel_checks.hpp"
#include "ops/contracted_ipe.hpp"
#include "ref/contract.hpp"
#include "ref/contracted_ipe.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

struct IpeRays {
  std::vector<float> origins, directions, radii, t_edges;
  size_t n_rays = 0, n_samples = 0;

  void add(std::array<float, 3> origin, std::array<float, 3> direction, float radius, const std::vector<float>& t) {
    REQUIRE(t.size() == n_samples + 1);
    origins.insert(origins.end(), origin.begin(), origin.end());
    directions.insert(directions.end(), direction.begin(), direction.end());
    radii.push_back(radius);
    t_edges.insert(t_edges.end(), t.begin(), t.end());
    ++n_rays;
  }
};

// Edges by the reciprocal warp between near and far (the official 360 spacing) at sorted uniform s.
std::vector<float> reciprocal_edges(std::mt19937& rng, size_t n, double near, double far) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<double> s(n + 1);
  for (auto& x : s) x = unit(rng);
  std::sort(s.begin(), s.end());
  s.front() = 0.0;
  std::vector<float> t;
  for (double x : s) t.push_back(static_cast<float>(ref::ray_warp_s_to_t_of(x, 1.0 / near, 1.0 / far)));
  return t;
}

IpeRays random_and_hard_rays(size_t n_random) {
  IpeRays rays;
  rays.n_samples = 16;
  std::mt19937 rng(45);
  std::uniform_real_distribution<float> box(-1.5f, 1.5f);
  std::normal_distribution<float> normal;
  for (size_t i = 0; i < n_random; ++i) {
    rays.add({box(rng), box(rng), box(rng)}, {normal(rng), normal(rng), normal(rng)},
             static_cast<float>(test::log_uniform(rng, 1e-4, 0.05)), reciprocal_edges(rng, rays.n_samples, 0.2, 1e6));
  }
  const size_t n = rays.n_samples;
  auto geometric = [&](double from, double to) {
    std::vector<float> t;
    for (size_t k = 0; k <= n; ++k) t.push_back(static_cast<float>(from * std::pow(to / from, double(k) / n)));
    return t;
  };
  // Far beyond any far bound, to t = 1e18 (`far` is refused beyond: the frustum's variances ~ t² overflow float32
  // from t ≈ 1e19, in the Gaussian stage itself).
  rays.add({0.2f, -0.1f, 0.3f}, {0.6f, -0.7f, 0.4f}, 1e-3f, geometric(1e3, 1e18));
  rays.add({0.0f, 0.0f, 2.0f}, {0.0f, 0.0f, -1.0f}, 2e-3f, geometric(0.2, 1e6));         // axis-aligned: off = 0
  rays.add({0.1f, 0.1f, 0.1f}, {1.0f, 0.5f, 0.2f}, 0.8f, geometric(0.2, 1e6));           // a cone far wider than a pixel
  rays.add({-0.3f, 0.2f, 0.1f}, {0.2f, 0.9f, -0.3f}, 1e-7f, geometric(0.2, 0.25));       // a thin cone, short intervals
  rays.add({0.0f, 0.0f, 0.0f}, {0.0f, 0.6f, 0.8f}, 1e-3f, std::vector<float>(n + 1, 0.7f));  // zero-width intervals
  std::vector<float> sphere;
  for (size_t k = 0; k <= n; ++k) sphere.push_back(0.9f + 0.2f * static_cast<float>(k) / n);  // |μ| around 1
  rays.add({0.0f, 0.0f, 0.0f}, {1.0f, 0.0f, 0.0f}, 4e-3f, sphere);
  return rays;
}

struct Encoded {
  std::vector<float> kernel;
  std::vector<double> reference, bound;
};

// The kernel built with a sincos every `sincos_every` degrees (0: the device's default) and the reference.
Encoded encode_both(const IpeRays& rays, const EncodingOptions& encoding, const std::vector<double>& ref_basis,
                    int sincos_every = 0) {
  auto& ctx = test::test_context();
  const GaussianOptions cone{RayShape::cone};
  ops::ContractedIpe stage(ctx, cone, 2, sincos_every);
  ops::RayBundle bundle(ctx, rays.n_rays);
  bundle.origins.upload(ctx, rays.origins);
  bundle.directions.upload(ctx, rays.directions);
  bundle.radii.upload(ctx, rays.radii);
  auto t = test::upload(ctx, rays.t_edges, "t_edges");
  const size_t rows = rays.n_rays * rays.n_samples, width = stage.width(encoding);
  auto features = test::filled(ctx, rows * width, 7.0f, "features");
  stage.fwd(encoding, {bundle, t, rays.n_rays, rays.n_samples}, features);
  Encoded out;
  out.kernel = features.download(ctx);
  const auto o = test::to_double(rays.origins), d = test::to_double(rays.directions), r = test::to_double(rays.radii),
             te = test::to_double(rays.t_edges);
  ref::contracted_ipe_fwd(cone, encoding, o, d, r, te, ref_basis, out.reference, rays.n_rays, rays.n_samples);
  std::vector<double> float_basis;
  for (float b : icosahedron_basis_floats(2)) float_basis.push_back(b);
  out.bound = ref::contracted_ipe_fwd_float32_bound(cone, encoding, stage.sincos_every(), o, d, r, te, float_basis,
                                                     rays.n_rays,
                                                     rays.n_samples);
  return out;
}

std::vector<double> kernel_basis() {
  std::vector<double> out;
  for (float b : icosahedron_basis_floats(2)) out.push_back(b);
  return out;
}

EncodingOptions official_degrees() {
  EncodingOptions encoding;
  encoding.min_deg = 0;
  encoding.max_deg = 12;
  return encoding;
}

// Elements beyond their bound, and the worst ratio.
std::pair<size_t, double> beyond(const Encoded& e) {
  size_t failures = 0;
  double worst = 0;
  for (size_t i = 0; i < e.reference.size(); ++i) {
    const double ratio = std::abs(e.kernel[i] - e.reference[i]) / e.bound[i];
    if (!(ratio <= 1.0)) ++failures;
    worst = std::max(worst, ratio);
  }
  return {failures, worst};
}

}  // namespace

TEST_CASE("contracted IPE: the kernel equals the reference within its float32 bound, hard cases finite") {
  const IpeRays rays = random_and_hard_rays(test::batch_for_device(200, 20));
  // A sincos per degree, and every 4 degrees with angle doubling between (the CPU default).
  Encoded e;
  for (int sincos_every : {1, 4}) {
    CAPTURE(sincos_every);
    e = encode_both(rays, official_degrees(), kernel_basis(), sincos_every);
    REQUIRE(e.kernel.size() == rays.n_rays * rays.n_samples * 504);
    CHECK(test::all_finite(e.kernel));
    const auto result = beyond(e);  // not a structured binding: clang refuses one in INFO's lambda
    const size_t failures = result.first;
    const double worst = result.second;
    INFO("worst error " << worst << " x bound");
    CHECK(failures == 0);
  }
  // The bound is a working one: over the features it is small (a bound of 1 would let anything pass).
  std::vector<double> sorted = e.bound;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted[sorted.size() / 2], p90 = sorted[sorted.size() * 9 / 10];
  MESSAGE("contracted IPE bounds: median " << median << ", 90th percentile " << p90 << ", largest " << sorted.back());
  CHECK(median < 3e-4);
  CHECK(p90 < 1e-2);
}

TEST_CASE("contracted IPE: a changed basis order or degree scale is beyond the bound") {
  const IpeRays rays = random_and_hard_rays(test::batch_for_device(40, 10));
  // The reference on the basis with two directions swapped: the kernel's features must not pass for it.
  auto swapped = kernel_basis();
  for (int a = 0; a < 3; ++a) std::swap(swapped[3 * 4 + a], swapped[3 * 5 + a]);
  CHECK(beyond(encode_both(rays, official_degrees(), swapped)).first > 0);
  // Degrees 1..12 instead of 0..11 (every scale doubled).
  EncodingOptions shifted;
  shifted.min_deg = 1;
  shifted.max_deg = 13;
  Encoded e = encode_both(rays, official_degrees(), kernel_basis());
  const Encoded other = encode_both(rays, shifted, kernel_basis());
  e.reference = other.reference;
  CHECK(beyond(e).first > 0);
}

TEST_CASE("contracted IPE: refuses a degree range that is empty or out of bounds") {
  auto& ctx = test::test_context();
  ops::ContractedIpe stage(ctx, {RayShape::cone}, 2);
  ops::RayBundle bundle(ctx, 1);
  auto t = test::filled(ctx, 3, 1.0f, "t_edges");
  auto features = test::filled(ctx, 2 * 504, 0.0f, "features");
  EncodingOptions empty;
  empty.min_deg = 3;
  empty.max_deg = 3;
  CHECK_THROWS_WITH_AS(stage.fwd(empty, {bundle, t, 1, 2}, features), doctest::Contains("not a valid range"), Error);
  EncodingOptions wide = official_degrees();
  wide.max_deg = 14;  // 2·14·21 = 588 features per row: the buffer holds 504
  CHECK_THROWS_AS(stage.fwd(wide, {bundle, t, 1, 2}, features), Error);
  CHECK_THROWS_WITH_AS(icosahedron_basis(0), doctest::Contains("outside 1..64"), Error);
  CHECK(icosahedron_basis(1).size() == 6);  // the icosahedron's 12 vertices, one of each antipodal pair
}
