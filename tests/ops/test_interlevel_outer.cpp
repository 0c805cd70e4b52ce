// mip-NeRF 360's interlevel loss (kernels/interlevel_outer.cl) against the double reference
// (host/ref/interlevel_outer.hpp, which tests/official pins to multinerf): the reference's outer measure against a
// brute-force overlap test; the kernel's forward and backward against the reference on random batches and hard cases
// (an empty NeRF histogram, all NeRF weight in one interval, proposal weights of 0 and of 1e30, NeRF edges past the
// proposal's, every proposal edge on a NeRF edge); the reference's backward against finite differences.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "histogram_pairs.hpp"
#include "kernel_checks.hpp"
#include "ops/interlevel_outer.hpp"
#include "ref/interlevel.hpp"
#include "ref/interlevel_outer.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;
using test::kUnitRoundoff;

namespace {

// Random rays, then the hard cases.
using OuterBatch = test::HistogramPairs;

OuterBatch outer_batch() {
  std::mt19937 rng(20261202);
  OuterBatch b;
  b.n = 12;
  b.m = 20;
  for (int i = 0; i < 24; ++i) {
    test::add_histogram_pair(b, test::random_sorted_edges(rng, b.n + 1, 0, 1), test::random_weights(rng, b.n, 0.9f), test::random_sorted_edges(rng, b.m + 1, 0, 1),
                  test::random_weights(rng, b.m, 0.7f));
  }
  const auto c = test::random_sorted_edges(rng, b.n + 1, 0, 1), cp = test::random_sorted_edges(rng, b.m + 1, 0, 1);
  test::add_histogram_pair(b, c, std::vector<float>(b.n, 0.0f), cp, test::random_weights(rng, b.m, 1));  // empty NeRF histogram
  std::vector<float> spike(b.n, 0.0f);
  spike[5] = 1.0f;
  test::add_histogram_pair(b, c, spike, cp, std::vector<float>(b.m, 0.0f));             // all mass, no proposal weight
  test::add_histogram_pair(b, c, test::random_weights(rng, b.n, 1), cp, std::vector<float>(b.m, 1e30f));  // huge proposal weights
  test::add_histogram_pair(b, test::random_sorted_edges(rng, b.n + 1, -0.5f, 1.5f), test::random_weights(rng, b.n, 1), cp, test::random_weights(rng, b.m, 1));
  std::vector<float> on_edges(b.m + 1);
  for (size_t k = 0; k <= b.m; ++k) on_edges[k] = c[std::min(k, b.n)];  // proposal edges on NeRF edges (and repeats)
  test::add_histogram_pair(b, c, test::random_weights(rng, b.n, 1), on_edges, test::random_weights(rng, b.m, 0.5f));
  return b;
}

// The reference's window for NeRF interval j, by brute force: every proposal interval [cp_k, cp_{k+1}) that the
// interval [c_j, c_{j+1}] touches, with stepfun.searchsorted's conventions at the ends (an edge equal to c_j counts
// from its own interval on).
double brute_force_bound(const std::vector<double>& c, const std::vector<double>& cp, const std::vector<double>& wp,
                         size_t j) {
  const size_t m = wp.size();
  size_t lo = 0, hi = m;
  for (size_t k = 0; k <= m; ++k) {
    if (cp[k] <= c[j]) lo = k;
  }
  for (size_t k = m + 1; k-- > 0;) {
    if (cp[k] > c[j + 1]) hi = k;
  }
  double sum = 0;
  for (size_t k = lo; k < hi; ++k) sum += wp[k];
  return sum;
}

}  // namespace

TEST_CASE("outer interlevel: the reference's outer measure is the brute-force window sum") {
  const OuterBatch b = outer_batch();
  for (size_t ray = 0; ray < b.n_rays; ++ray) {
    const auto c = test::to_double({b.c.begin() + ray * (b.n + 1), b.c.begin() + (ray + 1) * (b.n + 1)});
    const auto cp = test::to_double({b.cp.begin() + ray * (b.m + 1), b.cp.begin() + (ray + 1) * (b.m + 1)});
    const auto wp = test::to_double({b.wp.begin() + ray * b.m, b.wp.begin() + (ray + 1) * b.m});
    std::vector<double> bound(b.n);
    ref::outer_bounds(c.data(), b.n, cp.data(), wp.data(), b.m, bound.data());
    for (size_t j = 0; j < b.n; ++j) {
      CAPTURE(ray);
      CAPTURE(j);
      const double expected = brute_force_bound(c, cp, wp, j);
      CHECK(std::abs(bound[j] - expected) <= 1e-12 * std::max(1.0, std::abs(expected)));
    }
  }
}

TEST_CASE("outer interlevel: forward and backward equal the double reference, hard cases finite") {
  auto& ctx = test::test_context();
  const OuterBatch b = outer_batch();
  const auto c = test::to_double(b.c), w = test::to_double(b.w), cp = test::to_double(b.cp), wp = test::to_double(b.wp);
  std::vector<double> ray_loss(b.n_rays), d_wp(b.n_rays * b.m);
  const float mult = 1.0f;
  const double scale = mult / static_cast<double>(b.n_rays * b.n);
  ref::outer_interlevel_fwd(c.data(), w.data(), cp.data(), wp.data(), ray_loss.data(), b.n_rays, b.n, b.m);
  ref::outer_interlevel_bwd(c.data(), w.data(), cp.data(), wp.data(), scale, d_wp.data(), b.n_rays, b.n, b.m);

  ops::OuterInterlevel stage(ctx);
  auto dc = test::upload(ctx, b.c, "c"), dw = test::upload(ctx, b.w, "w"), dcp = test::upload(ctx, b.cp, "cp");
  auto dwp = test::upload(ctx, b.wp, "wp");
  ocl::DeviceArray<float> k_loss(ctx, b.n_rays, "ray_loss"), k_grad(ctx, b.n_rays * b.m, "d_wp");
  const ops::InterlevelInputs in{dc, dw, dcp, dwp, b.n_rays, b.n, b.m};
  stage.fwd(in, k_loss);
  stage.bwd(in, mult, b.n_rays, k_grad);
  const auto loss = k_loss.download(ctx), grad = k_grad.download(ctx);
  CHECK(test::all_finite(loss));
  CHECK(test::all_finite(grad));
  // Per ray: each NeRF interval's bound is a sum of up to M + 1 float terms, the loss term moves by 2e/s times its
  // error; the bounds below are those roundings with the magnitudes the reference gives (|loss_j| ≤ w_j here, e ≤ w).
  MIPNERF_CHECK_CLOSE("ray loss", loss, ray_loss, [&](size_t ray) {
    double tol = 0;
    for (size_t j = 0; j < b.n; ++j) {
      const double wj = w[ray * b.n + j];
      tol += 2 * (b.m + 8) * kUnitRoundoff * wj * (1 + 2 * wj / (wj + ref::kInterlevelEps));
    }
    return tol + 1e-30;
  });
  // Each d_wp_k sums ≤ N terms of scale·2e/s ≤ 2·scale each, each known to (M + 8) roundings relative to its size.
  MIPNERF_CHECK_CLOSE("d_wp", grad, d_wp, [&](size_t) { return 2 * scale * b.n * (b.m + 8) * kUnitRoundoff; });
  // The hard cases say what they should: no proposal weight → every window's loss is w_j (e = w, e²/(w+ε) ≈ w).
  CHECK(std::abs(ray_loss[25] - 1.0) < 1e-6);
  CHECK(ray_loss[24] == 0.0);  // an empty NeRF histogram costs nothing
  CHECK(ray_loss[26] == 0.0);  // a huge proposal bound covers everything
}

TEST_CASE("outer interlevel: the reference's backward against finite differences") {
  OuterBatch b = outer_batch();
  const auto c = test::to_double(b.c), w = test::to_double(b.w), cp = test::to_double(b.cp);
  // Proposal weights away from the kinks (e = 0) where the loss is not differentiable: the random rays only.
  const size_t rays = 24;
  std::vector<double> wp = test::to_double({b.wp.begin(), b.wp.begin() + rays * b.m});
  const double scale = 1.0 / static_cast<double>(rays * b.n);
  std::vector<double> grad(rays * b.m);
  ref::outer_interlevel_bwd(c.data(), w.data(), cp.data(), wp.data(), scale, grad.data(), rays, b.n, b.m);
  const auto objective = [&](const std::vector<double>& values) {
    std::vector<double> ray_loss(rays);
    ref::outer_interlevel_fwd(c.data(), w.data(), cp.data(), values.data(), ray_loss.data(), rays, b.n, b.m);
    return ref::outer_interlevel_loss(ray_loss, b.n, 1.0);
  };
  const auto check = test::central_differences(wp, grad, objective, 1, 1e-7);
  INFO("worst " << check.worst << " largest gradient " << check.largest_gradient);
  CHECK(check.largest_gradient > 0);
  CHECK(check.worst <= 1e-6 * check.largest_gradient);
}
