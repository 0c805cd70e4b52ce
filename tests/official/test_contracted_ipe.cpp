// mip-NeRF 360's encoding of contracted frustums, our basis (core/geodesic_basis.hpp), reference
// (host/ref/contracted_ipe.hpp) and kernel (kernels/contracted_ipe.cl) against the official multinerf functions' own
// outputs (fixtures/multinerf_contracted_ipe.json, written by make_contracted_ipe_vectors.py): geopoly.generate_basis,
// and for six rays (origins inside and outside the ball, an axis-aligned one, a wide cone far out, a tiny cone, intervals
// around the unit sphere) with reciprocal-warped intervals to t = 1e6: cast_rays(diag=False) → track_linearize(contract)
// → lift_and_diagonalize → integrated_pos_enc(0, 12). The official math ran in float64.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/geodesic_basis.hpp"
#include "official_fixtures.hpp"
#include "ops/contracted_ipe.hpp"
#include "ops/ray_bundle.hpp"
#include "ref/contracted_ipe.hpp"
#include "ref/gaussian.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

io::Json contracted_ipe_fixture() { return official::multinerf_fixture("multinerf_contracted_ipe.json"); }

struct FixtureRay {
  std::vector<double> origin, direction, radius, t_edges;
  std::vector<double> lifted_means, lifted_vars, features;
  size_t n_samples = 0, feature_rows = 0;
};

FixtureRay fixture_ray(const io::Json& r) {
  FixtureRay ray;
  ray.origin = official::flat(r.at("origin"), {3});
  ray.direction = official::flat(r.at("direction"), {3});
  ray.radius = {r.at("radius").get<double>()};
  ray.t_edges = official::flat(r.at("t_edges"));
  ray.n_samples = ray.t_edges.size() - 1;
  ray.lifted_means = official::flat(r.at("lifted_means"), {ray.n_samples, 21});
  ray.lifted_vars = official::flat(r.at("lifted_vars"), {ray.n_samples, 21});
  ray.features = official::flat(r.at("features"));
  ray.feature_rows = ray.features.size() / 504;
  REQUIRE(ray.features.size() == ray.feature_rows * 504);
  return ray;
}

std::vector<double> flat_basis(const std::vector<std::array<double, 3>>& basis) {
  std::vector<double> out;
  for (const auto& b : basis) out.insert(out.end(), b.begin(), b.end());
  return out;
}

// The official's float64 rounding of a lifted variance: its J Σ Jᵀ (jax.linearize) is within ~1e-16 of (a + b)² N_Σ
// per entry (tests/official/test_contract.cpp), N_Σ the sum of the world covariance's |entries|; a projection sums
// nine of them with weights |b_i b_j| ≤ 1: 1e-13 · 9 (a + b)² N_Σ holds it with room.
std::vector<double> lifted_var_scale(const FixtureRay& ray) {
  std::vector<double> means, covs, off;
  ref::gaussian_full_fwd({RayShape::cone}, ray.origin, ray.direction, ray.radius, ray.t_edges, means, covs, off, 1,
                         ray.n_samples);
  std::vector<double> scale(ray.n_samples);
  for (size_t i = 0; i < ray.n_samples; ++i) {
    const double r = std::max(1.0, std::hypot(means[3 * i], means[3 * i + 1], means[3 * i + 2]));
    const double a = (2 * r - 1) / (r * r), b = 1 / (r * r);
    double n = 0;
    for (int k = 0; k < 3; ++k) n += std::abs(covs[3 * i + k]) + 2 * std::abs(off[3 * i + k]);
    scale[i] = 9e-13 * (a + b) * (a + b) * n;
  }
  return scale;
}

// A feature's error from its lifted pair's: 2^l·Δm + ½·4^l·Δv·exp(−½·4^l·(v − Δv)), plus 1e-14 for the float64
// sin, cos and exp themselves.
double feature_bound(double mean_error, double var_error, double var, size_t l) {
  const double scale = std::ldexp(1.0, static_cast<int>(l));
  return scale * mean_error + 0.5 * scale * scale * var_error * std::exp(-0.5 * scale * scale * (var - var_error)) +
         1e-14;
}

}  // namespace

TEST_CASE("multinerf contracted IPE: the icosahedron basis is the official's, in its order") {
  const io::Json fixture = contracted_ipe_fixture();
  const auto official_basis = official::flat(fixture.at("basis"), {21, 3});
  const auto ours = flat_basis(icosahedron_basis(2));
  REQUIRE(ours.size() == official_basis.size());
  OFFICIAL_CHECK_AGREES("basis", ours, official_basis, official::constant_bound(1e-15));
  // The float basis the kernel holds is the official's float64 one rounded (its jnp.array without x64).
  const auto floats = icosahedron_basis_floats(2);
  for (size_t i = 0; i < floats.size(); ++i) CHECK(floats[i] == static_cast<float>(official_basis[i]));
}

TEST_CASE("multinerf contracted IPE: lifted Gaussians and features, our reference and kernel") {
  const io::Json fixture = contracted_ipe_fixture();
  REQUIRE(fixture.at("min_deg").get<int>() == 0);
  REQUIRE(fixture.at("max_deg").get<int>() == 12);
  const auto basis = official::flat(fixture.at("basis"), {21, 3});
  std::vector<double> float_basis(basis.size());
  for (size_t i = 0; i < basis.size(); ++i) float_basis[i] = static_cast<float>(basis[i]);
  const GaussianOptions cone{RayShape::cone};
  EncodingOptions encoding;
  encoding.min_deg = 0;
  encoding.max_deg = 12;
  auto& ctx = test::test_context();
  ops::ContractedIpe stage(ctx, cone, 2);
  REQUIRE(stage.n_basis() == 21);
  REQUIRE(stage.width(encoding) == 504);
  size_t rays_seen = 0;
  for (const auto& r : fixture.at("rays")) {
    const FixtureRay ray = fixture_ray(r);
    CAPTURE(r.at("name").get<std::string>());
    ++rays_seen;
    std::vector<double> means, covs, off, lifted_means, lifted_vars;
    ref::contracted_gaussians(cone, ray.origin, ray.direction, ray.radius, ray.t_edges, means, covs, off, 1,
                              ray.n_samples);
    ref::project_gaussians(means, covs, off, basis, lifted_means, lifted_vars, ray.n_samples);
    const auto var_scale = lifted_var_scale(ray);
    OFFICIAL_CHECK_AGREES("reference lifted means", lifted_means, ray.lifted_means, official::constant_bound(1e-14));
    OFFICIAL_CHECK_AGREES("reference lifted vars", lifted_vars, ray.lifted_vars,
                          [&](size_t i) { return var_scale[i / 21] + 1e-15 * std::abs(ray.lifted_vars[i]); });

    std::vector<double> features;
    ref::contracted_ipe_fwd(cone, encoding, ray.origin, ray.direction, ray.radius, ray.t_edges, basis, features, 1,
                            ray.n_samples);
    auto ref_feature_bound = [&](size_t i) {
      const size_t row = i / 504, l = (i % 252) / 21, k = i % 21;
      const double v = ray.lifted_vars[row * 21 + k];
      return feature_bound(1e-14, var_scale[row] + 1e-15 * std::abs(v), v, l);
    };
    OFFICIAL_CHECK_AGREES("reference features", features, ray.features, ref_feature_bound);

    // The kernel: its float32 bound against our reference on the same float inputs (the basis as the kernel holds it),
    // plus what the float basis itself changes (computed: our reference on either basis), plus the official's rounding.
    ops::RayBundle bundle(ctx, 1);
    bundle.origins.upload(ctx, official::as_float(ray.origin));
    bundle.directions.upload(ctx, official::as_float(ray.direction));
    bundle.radii.upload(ctx, official::as_float(ray.radius));
    auto t_dev = official::upload(ctx, official::as_float(ray.t_edges), "t_edges");
    ocl::DeviceArray<float> k_features(ctx, ray.n_samples * 504, "features");
    stage.fwd(encoding, {bundle, t_dev, 1, ray.n_samples}, k_features);
    std::vector<double> float_basis_features;
    ref::contracted_ipe_fwd(cone, encoding, ray.origin, ray.direction, ray.radius, ray.t_edges, float_basis,
                            float_basis_features, 1, ray.n_samples);
    const auto bound = ref::contracted_ipe_fwd_float32_bound(cone, encoding, stage.sincos_every(), ray.origin,
                                                             ray.direction, ray.radius, ray.t_edges, float_basis, 1,
                                                             ray.n_samples);
    OFFICIAL_CHECK_AGREES("kernel features", k_features.download(ctx), ray.features, [&](size_t i) {
      return bound[i] + std::abs(float_basis_features[i] - features[i]) + ref_feature_bound(i);
    });
  }
  CHECK(rays_seen == 6);
}
