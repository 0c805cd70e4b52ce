// Zip-NeRF's spline interlevel loss (kernels/interlevel.cl) against the double reference (host/ref/interlevel.hpp,
// which tests/official pins to camp_zipnerf): the reference's blur against an independent closed form (the box blur
// as a second difference of the doubly integrated histogram); the kernel's forward and backward against the reference
// under per-element bounds derived from the walk's magnitudes; hard cases (empty histograms, all weight in one
// interval, blurs far wider and far narrower than the intervals, proposal weights of 0 under NeRF mass, zero-width
// intervals, queries past the histogram); the backward against finite differences on the reference and the kernel.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "histogram_pairs.hpp"
#include "kernel_checks.hpp"
#include "ops/interlevel.hpp"
#include "ref/interlevel.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;
using test::kUnitRoundoff;

namespace {

using InterlevelBatch = test::HistogramPairs;  // n = 16 NeRF and m = 12 proposal intervals a ray

// Random rays plus the hard cases: an empty NeRF histogram; all weight in one interval (narrower than most blurs);
// zero-width intervals in c and in cp; proposal weights of 0 where the NeRF has mass; queries reaching past [0, 1].
InterlevelBatch interlevel_batch(std::mt19937& rng) {
  InterlevelBatch b;
  for (int i = 0; i < 10; ++i) {
    test::add_histogram_pair(b, test::random_sorted_edges(rng, b.n + 1, 0.0f, 1.0f), test::random_weights(rng, b.n, 1.0f),
                       test::random_sorted_edges(rng, b.m + 1, 0.0f, 1.0f), test::random_weights(rng, b.m, 1.0f));
  }
  // Empty: all w = 0.
  test::add_histogram_pair(b, test::random_sorted_edges(rng, b.n + 1, 0.0f, 1.0f), std::vector<float>(b.n, 0.0f),
                     test::random_sorted_edges(rng, b.m + 1, 0.0f, 1.0f), test::random_weights(rng, b.m, 1.0f));
  // One interval of width 0.004 carries everything.
  {
    std::vector<float> c = test::random_sorted_edges(rng, b.n + 1, 0.0f, 1.0f), w(b.n, 0.0f);
    c[8] = 0.5f;
    c[9] = 0.504f;
    std::sort(c.begin(), c.end());
    const size_t k = std::find(c.begin(), c.end(), 0.5f) - c.begin();
    w[k] = 1.0f;
    test::add_histogram_pair(b, c, w, test::random_sorted_edges(rng, b.m + 1, 0.0f, 1.0f), test::random_weights(rng, b.m, 1.0f));
  }
  // Zero-width intervals in both histograms (c's carries weight, which weight_to_pdf drops); queries past [0, 1].
  {
    std::vector<float> c = test::random_sorted_edges(rng, b.n + 1, 0.0f, 1.0f), cp = test::random_sorted_edges(rng, b.m + 1, -0.2f, 1.2f);
    c[5] = c[4];
    c[11] = c[10];
    cp[6] = cp[5];
    test::add_histogram_pair(b, c, test::random_weights(rng, b.n, 1.0f), cp, test::random_weights(rng, b.m, 1.0f));
  }
  // The proposal misses mass: wp = 0 on half the intervals.
  {
    std::vector<float> wp = test::random_weights(rng, b.m, 1.0f);
    std::fill(wp.begin(), wp.begin() + 6, 0.0f);
    test::add_histogram_pair(b, test::random_sorted_edges(rng, b.n + 1, 0.0f, 1.0f), test::random_weights(rng, b.n, 1.0f),
                       test::random_sorted_edges(rng, b.m + 1, 0.0f, 1.0f), wp);
  }
  return b;
}

struct InterlevelDeviceRun {
  std::vector<float> w_blur, ray_loss, d_wp;
};

InterlevelDeviceRun run_interlevel_device(const InterlevelBatch& b, float halfwidth, float mult,
                                          const std::vector<float>* w_blur_in = nullptr) {
  auto& ctx = test::test_context();
  ops::SplineInterlevel stage(ctx);
  auto c = test::upload(ctx, b.c, "c"), w = test::upload(ctx, b.w, "w");
  auto cp = test::upload(ctx, b.cp, "cp"), wp = test::upload(ctx, b.wp, "wp");
  auto w_blur = test::filled(ctx, b.n_rays * b.m, 7.0f, "w_blur");
  auto ray_loss = test::filled(ctx, b.n_rays, 7.0f, "ray_loss");
  auto d_wp = test::filled(ctx, b.n_rays * b.m, 7.0f, "d_wp");
  const ops::InterlevelInputs in{c, w, cp, wp, b.n_rays, b.n, b.m};
  stage.fwd(in, halfwidth, w_blur, ray_loss);
  InterlevelDeviceRun run{w_blur.download(ctx), ray_loss.download(ctx), {}};
  if (w_blur_in) w_blur.upload(ctx, *w_blur_in);  // the backward alone, from the reference's w_blur
  stage.bwd(in, w_blur, mult, b.n_rays, d_wp);
  run.d_wp = d_wp.download(ctx);
  return run;
}

struct InterlevelReference {
  std::vector<double> w_blur, ray_loss, d_wp;
};

InterlevelReference run_interlevel_reference(const InterlevelBatch& b, double halfwidth, double grad_scale) {
  InterlevelReference r{std::vector<double>(b.n_rays * b.m), std::vector<double>(b.n_rays),
                        std::vector<double>(b.n_rays * b.m)};
  const auto c = test::to_double(b.c), w = test::to_double(b.w), cp = test::to_double(b.cp), wp = test::to_double(b.wp);
  ref::spline_interlevel_fwd(c.data(), w.data(), cp.data(), wp.data(), halfwidth, r.w_blur.data(), r.ray_loss.data(),
                             b.n_rays, b.n, b.m);
  ref::spline_interlevel_bwd(r.w_blur.data(), wp.data(), grad_scale, r.d_wp.data(), b.n_rays * b.m);
  return r;
}

// ∫_{−∞}^{x} of the histogram's CDF: each interval [a, b] of weight v adds v · (x − a)² / (2(b − a)) inside it and
// v · ((b − a)/2 + x − b) past it; zero-width intervals carry no density (as weight_to_pdf).
double interlevel_cdf_integral(const double* c, const double* w, size_t n, double x) {
  double g = 0;
  for (size_t i = 0; i < n; ++i) {
    const double a = c[i], b = c[i + 1];
    if (!(b - a >= 1.1754943508222875e-38)) continue;
    if (x <= a) continue;
    g += x < b ? w[i] * (x - a) * (x - a) / (2 * (b - a)) : w[i] * ((b - a) / 2 + x - b);
  }
  return g;
}

// ∫_{q0}^{q1} of the histogram blurred by a box of half-width r: the box average is (CDF(x + r) − CDF(x − r)) / 2r,
// whose integral is a second difference of interlevel_cdf_integral.
double interlevel_closed_form(const double* c, const double* w, size_t n, double r, double q0, double q1) {
  auto G = [&](double x) { return interlevel_cdf_integral(c, w, n, x); };
  return (G(q1 + r) - G(q1 - r) - G(q0 + r) + G(q0 - r)) / (2 * r);
}

// Per element of w_blur, what float32 can move it by (ref::blur_and_resample_float32_bound, ray by ray).
std::vector<double> interlevel_w_blur_bound(const InterlevelBatch& b, double halfwidth) {
  std::vector<double> bound;
  const auto c = test::to_double(b.c), w = test::to_double(b.w), cp = test::to_double(b.cp);
  for (size_t ray = 0; ray < b.n_rays; ++ray) {
    const auto ray_bound = ref::blur_and_resample_float32_bound(&c[ray * (b.n + 1)], &w[ray * b.n], b.n,
                                                                &cp[ray * (b.m + 1)], b.m, halfwidth);
    for (double x : ray_bound) bound.push_back(x + 1e-30);
  }
  return bound;
}

}  // namespace

TEST_CASE("spline interlevel: the reference's blur is the closed-form box average, and keeps the mass") {
  std::mt19937 rng(4501);
  const InterlevelBatch b = interlevel_batch(rng);
  const auto c = test::to_double(b.c), w = test::to_double(b.w), cp = test::to_double(b.cp);
  for (double r : {0.03, 0.003, 0.5, 1e-5}) {
    CAPTURE(r);
    double worst = 0;
    for (size_t ray = 0; ray < b.n_rays; ++ray) {
      std::vector<double> w_blur(b.m);
      const double* rc = &c[ray * (b.n + 1)];
      const double* rq = &cp[ray * (b.m + 1)];
      ref::blur_and_resample_weights(rc, &w[ray * b.n], b.n, rq, b.m, r, w_blur.data());
      for (size_t j = 0; j < b.m; ++j) {
        const double expected = interlevel_closed_form(rc, &w[ray * b.n], b.n, r, rq[j], rq[j + 1]);
        worst = std::max(worst, std::abs(w_blur[j] - expected));
      }
    }
    // The closed form's second difference of O(1) values over 2r loses ~1e-16 / r.
    CHECK(worst <= 1e-12 / r);
  }
  // Queries covering [c_0 − r, c_N + r] collect every weight of the non-zero-width intervals.
  const std::vector<double> rc = {0.0, 0.1, 0.1, 0.4, 0.45, 1.0}, rw = {0.2, 0.3, 0.1, 0.25, 0.15};
  const std::vector<double> rq = {-1.0, 0.2, 0.3, 0.7, 2.0};
  std::vector<double> w_blur(4);
  ref::blur_and_resample_weights(rc.data(), rw.data(), 5, rq.data(), 4, 0.05, w_blur.data());
  CHECK(w_blur[0] + w_blur[1] + w_blur[2] + w_blur[3] == doctest::Approx(0.7).epsilon(1e-14));  // 0.3 was at 0.1
}

TEST_CASE("spline interlevel: forward and backward equal the double reference (wide, official and narrow blurs)") {
  std::mt19937 rng(4502);
  const InterlevelBatch b = interlevel_batch(rng);
  const float mult = 0.01f;
  const double grad_scale = static_cast<double>(static_cast<float>(double(mult) / (b.n_rays * b.m)));
  for (float r : {0.5f, 0.03f, 0.003f, 1e-5f}) {
    CAPTURE(r);
    const auto ref_run = run_interlevel_reference(b, r, grad_scale);
    const auto device = run_interlevel_device(b, r, mult, nullptr);
    const auto bound = interlevel_w_blur_bound(b, r);
    MIPNERF_CHECK_CLOSE("w_blur", device.w_blur, ref_run.w_blur, [&](size_t i) { return bound[i]; });
    // Each interval's loss e² / s moves by (2e + δ) δ / s for a w_blur error δ, plus its own few roundings.
    std::vector<double> loss_bound(b.n_rays, 0.0);
    for (size_t i = 0; i < b.n_rays * b.m; ++i) {
      const double s = b.wp[i] + ref::kInterlevelEps, e = std::max(0.0, ref_run.w_blur[i] - b.wp[i]);
      loss_bound[i / b.m] += (2 * e + bound[i]) * bound[i] / s +
                             (b.m + 8) * kUnitRoundoff * ref::interlevel_interval_loss(ref_run.w_blur[i], b.wp[i]);
    }
    MIPNERF_CHECK_CLOSE("ray_loss", device.ray_loss, ref_run.ray_loss, [&](size_t i) { return loss_bound[i]; });
    // The backward alone, from the reference's w_blur (rounded to float): a handful of roundings per element.
    const auto w_blur_f = test::to_float(ref_run.w_blur);
    std::vector<double> expected_d_wp(b.n_rays * b.m);
    const auto wp = test::to_double(b.wp);
    ref::spline_interlevel_bwd(test::to_double(w_blur_f).data(), wp.data(), grad_scale, expected_d_wp.data(),
                               expected_d_wp.size());
    const auto bwd_device = run_interlevel_device(b, r, mult, &w_blur_f);
    MIPNERF_CHECK_CLOSE("d_wp", bwd_device.d_wp, expected_d_wp,
                        [&](size_t i) { return 12 * kUnitRoundoff * std::abs(expected_d_wp[i]) + 1e-30; });
  }
}

TEST_CASE("spline interlevel: hard cases stay finite and exact where the answer is known") {
  std::mt19937 rng(4503);
  const InterlevelBatch b = interlevel_batch(rng);
  for (float r : {0.5f, 0.03f, 1e-5f}) {
    CAPTURE(r);
    const auto device = run_interlevel_device(b, r, 0.01f);
    REQUIRE(test::all_finite(device.w_blur));
    REQUIRE(test::all_finite(device.ray_loss));
    REQUIRE(test::all_finite(device.d_wp));
    // Ray 10 is empty: nothing to resample, no loss, no gradient.
    for (size_t j = 0; j < b.m; ++j) {
      CHECK(device.w_blur[10 * b.m + j] == 0.0f);
      CHECK(device.d_wp[10 * b.m + j] == 0.0f);
    }
    CHECK(device.ray_loss[10] == 0.0f);
    // Ray 13's proposal misses mass: wp = 0 under w_blur > 0 costs w_blur² / ε, large and finite, and pushes wp up.
    bool saw_missed_mass = false;
    for (size_t j = 0; j < 6; ++j) {
      const size_t i = 13 * b.m + j;
      if (device.w_blur[i] > 1e-3f) {
        saw_missed_mass = true;
        CHECK(device.d_wp[i] < 0.0f);
      }
    }
    CHECK(saw_missed_mass);
    CHECK(device.ray_loss[13] > 1e3f);
    // Wherever wp ≥ w_blur the interval costs nothing and takes no gradient.
    for (size_t i = 0; i < b.n_rays * b.m; ++i) {
      if (b.wp[i] >= device.w_blur[i]) CHECK(device.d_wp[i] == 0.0f);
    }
  }
  // The one-interval ray under a blur far narrower than its interval: every proposal interval inside or outside it
  // gets its overlap's share of the weight (1 / 0.004 per unit length).
  const auto device = run_interlevel_device(b, 1e-6f, 0.01f);
  const size_t ray = 11;
  const float* c = &b.c[ray * (b.n + 1)];
  const size_t k = std::find(c, c + b.n + 1, 0.5f) - c;
  REQUIRE(k < b.n);
  for (size_t j = 0; j < b.m; ++j) {
    const double q0 = b.cp[ray * (b.m + 1) + j], q1 = b.cp[ray * (b.m + 1) + j + 1];
    const double overlap = std::max(0.0, std::min(q1, double(c[k + 1])) - std::max(q0, double(c[k])));
    CHECK(std::abs(device.w_blur[ray * b.m + j] - overlap / (c[k + 1] - c[k])) <= 2e-3);
  }
}

// The loss is explicit in wp (w_blur is wp-free), so central differences of the reference's Σ ray_loss agree with
// its backward to the differences' truncation (h² f''' / 6, relative ~1e-10 at h = 1e-6 s) and roundoff.
TEST_CASE("spline interlevel: the backward is the forward's gradient (finite differences, reference and kernel)") {
  std::mt19937 rng(4504);
  const InterlevelBatch b = interlevel_batch(rng);
  const double r = 0.03, grad_scale = 1.0;
  const auto base = run_interlevel_reference(b, r, grad_scale);
  size_t checked = 0;
  for (size_t i = 0; i < b.n_rays * b.m; ++i) {
    const double s = b.wp[i] + ref::kInterlevelEps, e = base.w_blur[i] - b.wp[i];
    const double h = 1e-6 * s;
    if (std::abs(e) < 1e3 * h) continue;  // the kink of max(0, ·)
    // The whole forward of ray i / M with wp_i moved: its ray_loss.
    auto loss_at = [&](double wp_i) {
      const size_t ray = i / b.m;
      std::vector<double> c = test::to_double(b.c), w = test::to_double(b.w), cp = test::to_double(b.cp);
      std::vector<double> wp = test::to_double(b.wp), w_blur(b.m);
      wp[i] = wp_i;
      double ray_loss = 0;
      ref::spline_interlevel_fwd(&c[ray * (b.n + 1)], &w[ray * b.n], &cp[ray * (b.m + 1)], &wp[ray * b.m], r,
                                 w_blur.data(), &ray_loss, 1, b.n, b.m);
      return ray_loss;
    };
    const double fd = (loss_at(b.wp[i] + h) - loss_at(b.wp[i] - h)) / (2 * h);
    CHECK(std::abs(fd - base.d_wp[i]) <= 1e-6 * std::abs(base.d_wp[i]) + 1e-14 * base.ray_loss[i / b.m] / h);
    ++checked;
  }
  CHECK(checked > b.n_rays * b.m / 4);
  // The kernel: move one wp in float32, difference the kernel's ray loss (in double), against the kernel's gradient
  // for mult = 1 and one ray (grad_scale 1 / M per interval: the kernel's d_wp · R · M is ∂ray_loss/∂wp).
  const auto device = run_interlevel_device(b, float(r), 1.0f);
  size_t kernel_checked = 0;
  for (size_t i = 0; i < b.n_rays * b.m; i += 3) {
    const size_t ray = i / b.m;
    const double s = b.wp[i] + ref::kInterlevelEps, e = device.w_blur[i] - b.wp[i];
    if (!(e > 0.05 * s) || b.wp[i] < 1e-3f) continue;  // away from the kink, and wp's float steps fine enough
    InterlevelBatch up = b, down = b;
    up.wp[i] = b.wp[i] * (1 + 1e-3f);
    down.wp[i] = b.wp[i] * (1 - 1e-3f);
    const double fd = (double(run_interlevel_device(up, float(r), 1.0f).ray_loss[ray]) -
                       double(run_interlevel_device(down, float(r), 1.0f).ray_loss[ray])) /
                      (double(up.wp[i]) - double(down.wp[i]));
    const double grad = double(device.d_wp[i]) * double(b.n_rays * b.m);
    // Truncation h²(s + e)² / s⁴ ≤ 1e-6 (s + e)² / s² relative to s; roundoff of ~M + 8 u of the ray's loss over 2h.
    const double tol = 1e-6 * (s + e) * (s + e) / (s * s) +
                       (b.m + 8) * kUnitRoundoff * device.ray_loss[ray] / (double(up.wp[i]) - double(down.wp[i])) +
                       16 * kUnitRoundoff * std::abs(grad);
    CHECK(std::abs(fd - grad) <= tol);
    ++kernel_checked;
  }
  CHECK(kernel_checked >= 5);
}

TEST_CASE("spline interlevel: the host refuses bad shapes and half-widths") {
  auto& ctx = test::test_context();
  ops::SplineInterlevel stage(ctx);
  auto c = test::filled(ctx, 5, 0.0f, "c"), w = test::filled(ctx, 4, 0.0f, "w");
  auto cp = test::filled(ctx, 4, 0.0f, "cp"), wp = test::filled(ctx, 3, 0.0f, "wp");
  auto w_blur = test::filled(ctx, 3, 0.0f, "w_blur"), ray_loss = test::filled(ctx, 1, 0.0f, "ray_loss");
  CHECK_NOTHROW(stage.fwd({c, w, cp, wp, 1, 4, 3}, 0.03f, w_blur, ray_loss));
  CHECK_THROWS(stage.fwd({c, w, cp, wp, 1, 4, 3}, 0.0f, w_blur, ray_loss));
  CHECK_THROWS(stage.fwd({c, w, cp, wp, 1, 4, 3}, NAN, w_blur, ray_loss));
  CHECK_THROWS(stage.fwd({c, w, cp, wp, 2, 4, 3}, 0.03f, w_blur, ray_loss));
  CHECK_THROWS(stage.fwd({c, w, cp, wp, 1, 0, 3}, 0.03f, w_blur, ray_loss));
  CHECK_THROWS(stage.bwd({c, w, cp, wp, 1, 4, 3}, w_blur, 0.01f, 0, wp));
}
