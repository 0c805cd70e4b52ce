// mip-NeRF 360's max-dilation of a proposal histogram (kernels/dilate.cl) against the double reference
// (host/ref/dilate.hpp, which tests/official pins to multinerf): the reference's properties (the dilated pdf bounds the
// original everywhere, a dilation of 0 keeps the histogram's mass where it was), and the kernel against the reference
// on random histograms and hard cases (all weight in one narrow interval, zero-width intervals, an empty histogram,
// a dilation wider than the ray, a dilation of 0), within bounds from the knots' float32 rounding.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "kernel_checks.hpp"
#include "ops/dilate.hpp"
#include "ref/dilate.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;
using test::kUnitRoundoff;

namespace {

struct DilateBatch {
  std::vector<float> s, w;
  size_t n_rays = 0, n = 10;
};

void dilate_add_ray(DilateBatch& b, std::vector<float> s, std::vector<float> w) {
  REQUIRE(s.size() == b.n + 1);
  REQUIRE(w.size() == b.n);
  b.s.insert(b.s.end(), s.begin(), s.end());
  b.w.insert(b.w.end(), w.begin(), w.end());
  ++b.n_rays;
}

DilateBatch dilate_batch() {
  std::mt19937 rng(20261202);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  DilateBatch b;
  const auto edges = [&] {
    std::vector<float> s(b.n + 1);
    s.front() = 0.0f;
    s.back() = 1.0f;
    for (size_t i = 1; i < b.n; ++i) s[i] = u(rng);
    std::sort(s.begin(), s.end());
    return s;
  };
  const auto weights = [&] {
    std::vector<float> w(b.n);
    float sum = 0;
    for (auto& x : w) sum += (x = u(rng) * u(rng));
    for (auto& x : w) x /= sum;
    return w;
  };
  for (int i = 0; i < 20; ++i) dilate_add_ray(b, edges(), weights());
  std::vector<float> spike(b.n, 0.0f), narrow = edges();
  narrow[4] = 0.5f;
  narrow[5] = 0.5f + 1e-6f;
  std::sort(narrow.begin(), narrow.end());
  spike[4] = 1.0f;
  dilate_add_ray(b, narrow, spike);                         // all weight in an interval 1e-6 wide
  std::vector<float> repeated = edges();
  repeated[3] = repeated[4] = repeated[5];                  // zero-width intervals
  dilate_add_ray(b, repeated, weights());
  dilate_add_ray(b, edges(), std::vector<float>(b.n, 0.0f));  // an empty histogram
  return b;
}

std::vector<double> run_reference(const DilateBatch& b, double dilation, std::vector<double>& s_out) {
  std::vector<double> w_out;
  ref::max_dilate_weights_fwd(test::to_double(b.s), test::to_double(b.w), static_cast<float>(dilation), 0.0, 1.0,
                              s_out, w_out, b.n_rays, b.n);
  return w_out;
}

}  // namespace

TEST_CASE("dilate: the reference's dilated pdf bounds the original's, and no dilation keeps the mass in place") {
  const DilateBatch b = dilate_batch();
  for (double dilation : {0.0, 0.01, 0.1}) {
    CAPTURE(dilation);
    std::vector<double> s_out;
    const auto w_out = run_reference(b, dilation, s_out);
    const size_t m = 3 * b.n - 2;
    for (size_t ray = 0; ray < 20; ++ray) {  // the random rays: every interval wider than 0
      const double* s = &s_out[ray * (m + 1)];
      const double* w = &w_out[ray * m];
      CHECK(std::is_sorted(s, s + m + 1));
      // The mass between two original edges never shrinks under dilation, relative to the total.
      for (size_t i = 0; i < b.n; ++i) {
        const double lo = b.s[ray * (b.n + 1) + i], hi = b.s[ray * (b.n + 1) + i + 1];
        double mass = 0;
        for (size_t k = 0; k < m; ++k) {
          if (s[k] >= lo && s[k + 1] <= hi) mass += w[k];
        }
        if (dilation == 0.0) {
          CHECK(mass == doctest::Approx(b.w[ray * b.n + i]).epsilon(1e-5));
        } else {
          CHECK(mass >= b.w[ray * b.n + i] / (1.0 + 4 * dilation * b.n * 1e3) - 1e-12);
        }
      }
    }
  }
}

TEST_CASE("dilate: the kernel equals the double reference, hard cases finite") {
  auto& ctx = test::test_context();
  const DilateBatch b = dilate_batch();
  ops::MaxDilate stage(ctx);
  auto s_in = test::upload(ctx, b.s, "s"), w_in = test::upload(ctx, b.w, "w");
  const size_t edges = ops::dilated_edges(b.n), intervals = ops::dilated_intervals(b.n);
  ocl::DeviceArray<float> s_out(ctx, b.n_rays * edges, "s_out"), w_out(ctx, b.n_rays * intervals, "w_out");
  ocl::DeviceArray<uint32_t> scratch(ctx, b.n_rays * b.n, "scratch");
  for (double dilation : {0.0, 0.0025 + 0.5 / 64, 0.05, 2.0}) {
    CAPTURE(dilation);
    stage.fwd(s_in, w_in, b.n_rays, b.n, static_cast<float>(dilation), s_out, w_out, scratch);
    std::vector<double> ref_s;
    const auto ref_w = run_reference(b, dilation, ref_s);
    const auto s = s_out.download(ctx), w = w_out.download(ctx);
    CHECK(test::all_finite(s));
    CHECK(test::all_finite(w));
    // Knots: s ± d rounded once (and the reference's d is the float's value).
    MIPNERF_CHECK_CLOSE("dilated edges", s, ref_s, [&](size_t) { return 2 * kUnitRoundoff * (1 + dilation); });
    // Weights: each knot moves by ≤ that, so a weight by its pooled pdf times two such moves, then a few roundings,
    // then the renormalisation (the sum's own error, relative). The largest pdf of the ray stands for its pooled one.
    MIPNERF_CHECK_CLOSE("dilated weights", w, ref_w, [&](size_t i) {
      const size_t ray = i / intervals;
      double largest_pdf = 0, sum = 0;
      for (size_t k = 0; k < b.n; ++k) {
        const double width = std::max(1.42e-14, static_cast<double>(b.s[ray * (b.n + 1) + k + 1]) -
                                                    b.s[ray * (b.n + 1) + k]);
        largest_pdf = std::max(largest_pdf, b.w[ray * b.n + k] / width);
      }
      for (size_t k = 0; k < intervals; ++k) sum += ref_w[ray * intervals + k];
      const double knot = 4 * kUnitRoundoff * (1 + dilation) * largest_pdf / std::max(sum, 1e-30);
      return knot + (3 * b.n + 8) * kUnitRoundoff * (std::abs(ref_w[i]) + 1e-30) + knot * ref_w[i] * 3 * b.n;
    });
  }
  // The empty histogram stays empty (the ε² guard, no NaN), and the spike's mass stays near its interval.
  stage.fwd(s_in, w_in, b.n_rays, b.n, 0.01f, s_out, w_out, scratch);
  const auto w = w_out.download(ctx);
  for (size_t k = 0; k < intervals; ++k) CHECK(w[(b.n_rays - 1) * intervals + k] == 0.0f);
}
