// mip-NeRF 360's distortion loss (kernels/distortion.cl) against the double reference (host/ref/distortion.hpp, which
// tests/official pins to camp_zipnerf): the reference's O(N) form against eq. 15's double sum; the kernel's forward
// and backward (weights and edges) against the reference under bounds derived from their sums; hard cases (empty
// histograms, all weight in one interval, zero-width intervals, metric distances far from 0); the backward against
// finite differences on the reference and on the kernel.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "kernel_checks.hpp"
#include "ops/distortion.hpp"
#include "ref/distortion.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;
using test::kUnitRoundoff;

namespace {

struct DistortionBatch {
  std::vector<float> t, w;
  size_t n_rays = 0, n = 24;
};

// Random rays in [0, 1] and in [2, 6] (metric distances), plus: an empty ray (w = 0), all weight in one interval,
// zero-width intervals, weights that do not sum to 1.
DistortionBatch distortion_batch(std::mt19937& rng) {
  DistortionBatch b;
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  auto add = [&](float lo, float hi, int kind) {
    std::vector<float> t(b.n + 1), w(b.n);
    for (auto& x : t) x = lo + (hi - lo) * u(rng);
    std::sort(t.begin(), t.end());
    float sum = 0;
    for (auto& x : w) sum += (x = u(rng) * u(rng));
    for (auto& x : w) x /= sum;
    if (kind == 1) std::fill(w.begin(), w.end(), 0.0f);
    if (kind == 2) {
      std::fill(w.begin(), w.end(), 0.0f);
      w[7] = 1.0f;
    }
    if (kind == 3) {
      t[4] = t[3];
      t[12] = t[11];
      t[13] = t[11];
    }
    if (kind == 4) {
      for (auto& x : w) x *= 0.3f;
    }
    b.t.insert(b.t.end(), t.begin(), t.end());
    b.w.insert(b.w.end(), w.begin(), w.end());
    ++b.n_rays;
  };
  for (int i = 0; i < 8; ++i) add(0.0f, 1.0f, 0);
  for (int i = 0; i < 4; ++i) add(2.0f, 6.0f, 0);
  for (int kind = 1; kind <= 4; ++kind) add(0.0f, 1.0f, kind);
  return b;
}

struct DistortionRun {
  std::vector<float> ray_loss, d_w, d_t;
};

DistortionRun run_distortion_device(const DistortionBatch& b, float mult) {
  auto& ctx = test::test_context();
  ops::Distortion stage(ctx);
  auto t = test::upload(ctx, b.t, "t"), w = test::upload(ctx, b.w, "w");
  auto ray_loss = test::filled(ctx, b.n_rays, 7.0f, "ray_loss");
  auto d_w = test::filled(ctx, b.w.size(), 7.0f, "d_w"), d_t = test::filled(ctx, b.t.size(), 7.0f, "d_t");
  const ops::DistortionInputs in{t, w, b.n_rays, b.n};
  stage.fwd(in, ray_loss);
  stage.bwd(in, mult, b.n_rays, d_w, d_t);
  return {ray_loss.download(ctx), d_w.download(ctx), d_t.download(ctx)};
}

struct DistortionReference {
  std::vector<double> ray_loss, d_w, d_t;
};

DistortionReference run_distortion_reference(const DistortionBatch& b, double grad_scale) {
  DistortionReference r{std::vector<double>(b.n_rays), std::vector<double>(b.w.size()),
                        std::vector<double>(b.t.size())};
  const auto t = test::to_double(b.t), w = test::to_double(b.w);
  ref::distortion_fwd(t.data(), w.data(), r.ray_loss.data(), b.n_rays, b.n);
  ref::distortion_bwd(t.data(), w.data(), grad_scale, r.d_w.data(), r.d_t.data(), b.n_rays, b.n);
  return r;
}

}  // namespace

TEST_CASE("distortion: the reference's O(N) form is eq. 15's double sum") {
  std::mt19937 rng(4601);
  const DistortionBatch b = distortion_batch(rng);
  const auto t = test::to_double(b.t), w = test::to_double(b.w);
  const auto r = run_distortion_reference(b, 1.0);
  double largest = 0;
  for (size_t ray = 0; ray < b.n_rays; ++ray) {
    const double expected = ref::distortion_quadratic(&t[ray * (b.n + 1)], &w[ray * b.n], b.n);
    CHECK(std::abs(r.ray_loss[ray] - expected) <= 1e-14 * (expected + 1e-300));
    largest = std::max(largest, expected);
  }
  CHECK(largest > 0.1);
  CHECK(r.ray_loss[12] == 0.0);  // empty
  // All weight in one interval: only its own term, w² · width / 3.
  CHECK(r.ray_loss[13] == doctest::Approx((t[13 * (b.n + 1) + 8] - t[13 * (b.n + 1) + 7]) / 3).epsilon(1e-14));
}

TEST_CASE("distortion: forward and backward equal the double reference") {
  std::mt19937 rng(4602);
  const DistortionBatch b = distortion_batch(rng);
  const float mult = 0.01f;
  const double grad_scale = static_cast<float>(double(mult) / b.n_rays);
  const auto device = run_distortion_device(b, mult);
  const auto r = run_distortion_reference(b, grad_scale);
  REQUIRE(test::all_finite(device.ray_loss));
  REQUIRE(test::all_finite(device.d_w));
  REQUIRE(test::all_finite(device.d_t));
  // Every term is non-negative (w ≥ 0, t sorted): the sums' relative error grows with their length, ~4 roundings a
  // term (the edge difference, two products, the add) over N terms, and each edge difference's own.
  const double n = b.n;
  MIPNERF_CHECK_CLOSE("ray_loss", device.ray_loss, r.ray_loss,
                      [&](size_t i) { return (4 * n + 16) * kUnitRoundoff * r.ray_loss[i] + 1e-30; });
  MIPNERF_CHECK_CLOSE("d_w", device.d_w, r.d_w,
                      [&](size_t i) { return (4 * n + 16) * kUnitRoundoff * r.d_w[i] + 1e-30; });
  // ∂L/∂t: 2w (W_< − W_>) cancels; its error is ~(N + 8) u of 2 w W for each of the edge's two intervals.
  std::vector<double> bound(b.t.size());
  for (size_t ray = 0; ray < b.n_rays; ++ray) {
    double total = 0;
    for (size_t k = 0; k < b.n; ++k) total += b.w[ray * b.n + k];
    for (size_t e = 0; e <= b.n; ++e) {
      double near = 0;
      for (size_t k : {e - 1, e}) {
        if (k < b.n) near += b.w[ray * b.n + k] * (2 * total + b.w[ray * b.n + k]);
      }
      bound[ray * (b.n + 1) + e] = grad_scale * (n + 8) * kUnitRoundoff * near + 1e-30;
    }
  }
  MIPNERF_CHECK_CLOSE("d_t", device.d_t, r.d_t, [&](size_t i) { return bound[i]; });
  // The empty ray: no loss, no gradient.
  for (size_t k = 0; k < b.n; ++k) CHECK(device.d_w[12 * b.n + k] == 0.0f);
  CHECK(device.ray_loss[12] == 0.0f);
}

// Central differences of the reference (double) w.r.t. every weight and every edge of a few rays; the loss is
// piecewise quadratic, so only roundoff limits the agreement (midpoints kept apart from each other by the sort).
TEST_CASE("distortion: the backward is the forward's gradient (finite differences, reference and kernel)") {
  std::mt19937 rng(4603);
  const DistortionBatch b = distortion_batch(rng);
  const auto r = run_distortion_reference(b, 1.0);
  const auto t0 = test::to_double(b.t), w0 = test::to_double(b.w);
  auto ray_loss = [&](const std::vector<double>& t, const std::vector<double>& w, size_t ray) {
    double loss = 0;
    ref::distortion_fwd(&t[ray * (b.n + 1)], &w[ray * b.n], &loss, 1, b.n);
    return loss;
  };
  for (size_t ray : {0, 9, 13, 14}) {
    CAPTURE(ray);
    const double h = 1e-7;
    for (size_t k = 0; k < b.n; ++k) {
      auto up = w0, down = w0;
      up[ray * b.n + k] += h;
      down[ray * b.n + k] -= h;
      const double fd = (ray_loss(t0, up, ray) - ray_loss(t0, down, ray)) / (2 * h);
      CHECK(std::abs(fd - r.d_w[ray * b.n + k]) <= 1e-7);
    }
    // Edges: a move smaller than the gap to each neighbour keeps the order (ray 14's repeated edges are skipped:
    // moving one of them crosses |u_i − u_j|'s kink).
    for (size_t e = 0; e <= b.n; ++e) {
      const size_t i = ray * (b.n + 1) + e;
      const double gap_below = e > 0 ? t0[i] - t0[i - 1] : 1.0, gap_above = e < b.n ? t0[i + 1] - t0[i] : 1.0;
      if (std::min(gap_below, gap_above) < 1e-4) continue;
      auto up = t0, down = t0;
      up[i] += h;
      down[i] -= h;
      const double fd = (ray_loss(up, w0, ray) - ray_loss(down, w0, ray)) / (2 * h);
      CHECK(std::abs(fd - r.d_t[i]) <= 1e-7);
    }
  }
  // The kernel: move a weight and an edge of ray 0 in float32 and difference the kernel's ray loss.
  const auto device = run_distortion_device(b, float(b.n_rays));  // mult = R: the kernel's gradients are ∂ray_loss
  for (size_t k : {2, 11, 20}) {
    DistortionBatch up = b, down = b;
    up.w[k] += 1e-3f;
    down.w[k] -= 1e-3f;
    const double fd =
        (double(run_distortion_device(up, 1.0f).ray_loss[0]) - double(run_distortion_device(down, 1.0f).ray_loss[0])) /
        (double(up.w[k]) - double(down.w[k]));
    // Quadratic in w: no truncation; roundoff ~(4N + 16) u of the loss over the step.
    const double tol = (4 * b.n + 16) * kUnitRoundoff * device.ray_loss[0] / 1e-3 + 1e-5;
    CHECK(std::abs(fd - device.d_w[k]) <= tol);
  }
  for (size_t e : {3, 12, 21}) {
    DistortionBatch up = b, down = b;
    const float step = 1e-3f * std::min(b.t[e + 1] - b.t[e], b.t[e] - b.t[e - 1]);
    up.t[e] += step;
    down.t[e] -= step;
    const double fd =
        (double(run_distortion_device(up, 1.0f).ray_loss[0]) - double(run_distortion_device(down, 1.0f).ray_loss[0])) /
        (double(up.t[e]) - double(down.t[e]));
    const double tol = (4 * b.n + 16) * kUnitRoundoff * device.ray_loss[0] / step + 1e-4 * std::abs(device.d_t[e]);
    CHECK(std::abs(fd - device.d_t[e]) <= tol);
  }
}

TEST_CASE("distortion: the host refuses bad shapes") {
  auto& ctx = test::test_context();
  ops::Distortion stage(ctx);
  auto t = test::filled(ctx, 5, 0.0f, "t"), w = test::filled(ctx, 4, 0.0f, "w");
  auto ray_loss = test::filled(ctx, 1, 0.0f, "ray_loss"), d_t = test::filled(ctx, 5, 0.0f, "d_t");
  CHECK_NOTHROW(stage.fwd({t, w, 1, 4}, ray_loss));
  CHECK_THROWS(stage.fwd({t, w, 2, 4}, ray_loss));
  CHECK_THROWS(stage.fwd({t, w, 1, 0}, ray_loss));
  CHECK_THROWS(stage.bwd({t, w, 1, 4}, 0.01f, 0, w, d_t));
}
