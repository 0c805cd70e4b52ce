// Stratified sampling and merging (kernels/sample.cl): against the reference, linear in depth or disparity,
// deterministic or jittered, sortedness, degenerate ranges (near = far, far < near, a zero bound in disparity),
// reproducibility across chunkings, and the sorted union of two edge sets.
#include <doctest/doctest.h>

#include <algorithm>
#include <functional>

#include "kernel_checks.hpp"
#include "ops/sample.hpp"
#include "ref/sample.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;
using test::kUnitRoundoff;

namespace {

struct Ranges {
  std::vector<float> near, far;
};

Ranges random_ranges(size_t n_rays, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Ranges r;
  for (size_t i = 0; i < n_rays; ++i) {
    const double near = 0.1 + 3 * unit(rng);
    r.near.push_back(static_cast<float>(near));
    r.far.push_back(static_cast<float>(near + test::log_uniform(rng, 0.01, 10.0)));
  }
  return r;
}

std::vector<float> run_stratified(const SampleOptions& options, const Ranges& r, size_t n_samples, const RngKey& key,
                                  size_t first = 0, size_t count = SIZE_MAX,
                                  ops::SampleItems items = ops::SampleItems::device_default) {
  auto& ctx = test::test_context();
  count = std::min(count, r.near.size() - first);
  const std::vector<float> near(r.near.begin() + first, r.near.begin() + first + count);
  const std::vector<float> far(r.far.begin() + first, r.far.begin() + first + count);
  ops::RayBundle rays(ctx, count);
  rays.near.upload(ctx, near);
  rays.far.upload(ctx, far);
  auto t_edges = test::filled(ctx, count * (n_samples + 1), 7.0f, "t_edges");
  ops::Sample stage(ctx, options, items);
  REQUIRE((items == ops::SampleItems::device_default || stage.items() == items));
  stage.stratified({rays, count, n_samples}, t_edges, key);
  return t_edges.download(ctx);
}

}  // namespace

TEST_CASE("sample: stratified edges match the CPU reference, linear in depth or disparity, plain or jittered") {
  const size_t n_rays = 10000, n = 16;
  const Ranges r = random_ranges(n_rays, 61);
  const RngKey key{2024, 3, 500};
  for (bool lindisp : {false, true}) {
    for (bool randomized : {false, true}) {
      INFO("lindisp " << lindisp << ", randomized " << randomized);
      const SampleOptions options{lindisp, randomized};
      const auto dev = run_stratified(options, r, n, key);
      std::vector<double> t_edges;
      ref::sample_stratified_fwd(options, test::to_double(r.near), test::to_double(r.far), t_edges, n_rays, n, key);
      // Tolerances. Linear: s = k/N (≤ 2.5 ulp), near·(1 − s) + far·s: ≤ 6u·(near + far); jitter adds the
      // midpoints' and the interpolation's roundings, ≤ 6u·far more. Disparity: two divisions and a reciprocal
      // (2.5 ulp each) and a sum: ≤ 16u relative to t, plus the same 6u·far for jitter. Twice the bounds.
      MIPNERF_CHECK_CLOSE("t_edges", dev, t_edges, [&](size_t i) {
        const size_t ray = i / (n + 1);
        const double near = r.near[ray], far = r.far[ray];
        return lindisp ? 2 * (16 * kUnitRoundoff * std::abs(t_edges[i]) + 6 * kUnitRoundoff * far)
                       : 2 * 12 * kUnitRoundoff * (near + far);
      });
      for (size_t ray = 0; ray < n_rays; ++ray) {
        const float* t = dev.data() + ray * (n + 1);
        REQUIRE(std::is_sorted(t, t + n + 1));
        if (!lindisp) {
          // Linear edges hit near and far exactly: near·1 + far·0 and near·0 + far·1.
          if (!randomized) REQUIRE(t[0] == r.near[ray]);
          if (!randomized) REQUIRE(t[n] == r.far[ray]);
          REQUIRE(t[0] >= r.near[ray]);
          REQUIRE(t[n] <= r.far[ray]);
        }
      }
    }
  }
}

TEST_CASE("sample: an item per 16 groups of edges gives the per-group edges bit for bit, with shorter last runs") {
  // 128 samples: 129 edges in 33 groups of 4, two runs of 16 groups as uint16/float16 and the last group alone;
  // 70 samples: 71 edges, one run and 2 groups (the last with 3 edges). Sixteen Philox calls lane by lane and the
  // edge formula per lane (sample.cl), so the same edges.
  const size_t n_rays = test::batch_for_device(700, 40);
  const Ranges r = random_ranges(n_rays, 64);
  const RngKey key{77, 9, 1200};
  for (const size_t n : {size_t(128), size_t(70)}) {
    for (bool lindisp : {false, true}) {
      for (bool randomized : {false, true}) {
        INFO(n << " samples, lindisp " << lindisp << ", randomized " << randomized);
        const SampleOptions options{lindisp, randomized};
        CHECK(run_stratified(options, r, n, key, 0, SIZE_MAX, ops::SampleItems::per_vector) ==
              run_stratified(options, r, n, key, 0, SIZE_MAX, ops::SampleItems::per_group));
      }
    }
  }
}

TEST_CASE("sample: near = far and far < near give the reference's edges, finite, in depth or disparity") {
  // Degenerate ranges: near = far (positive, and both 0), far < near (both positive, and far = 0), and near = 0 <
  // far (an NDC scene's [0, 1] sampled in disparity). In disparity a zero bound is the guarded case: the official
  // 1/near·(1 − s) + 1/far·s gives ∞·0 = NaN at the other end's edge, the kernel and the reference the formula's
  // limit (0 at every edge the zero bound's term reaches). Elsewhere the edges are the official formula's,
  // decreasing when far < near.
  const std::vector<std::pair<float, float>> ranges = {{2.0f, 2.0f}, {0.5f, 0.5f}, {1e-3f, 1e-3f}, {7.25f, 7.25f},
                                                       {0.0f, 0.0f}, {6.0f, 2.0f}, {3.0f, 0.5f},   {1.0f, 0.999f},
                                                       {2.0f, 0.0f}, {0.0f, 1.0f}};
  const size_t n = 16, copies = 50;  // each range on 50 rays, so the jitter draws differ
  Ranges r;
  for (size_t c = 0; c < copies; ++c) {
    for (const auto& [near, far] : ranges) {
      r.near.push_back(near);
      r.far.push_back(far);
    }
  }
  const size_t n_rays = r.near.size();
  const RngKey key{77, 2, 40};
  for (bool lindisp : {false, true}) {
    for (bool randomized : {false, true}) {
      INFO("lindisp " << lindisp << ", randomized " << randomized);
      const SampleOptions options{lindisp, randomized};
      const auto dev = run_stratified(options, r, n, key);
      std::vector<double> t_edges;
      ref::sample_stratified_fwd(options, test::to_double(r.near), test::to_double(r.far), t_edges, n_rays, n, key);
      for (double t : t_edges) REQUIRE(std::isfinite(t));  // the reference's guard: a value for every range here
      // The bounds of the test above, which do not depend on the order of near and far: linear ≤ 12u·(near + far);
      // disparity ≤ 16u·|t| plus the jitter's midpoint and interpolation roundings, 6u of the larger bound (far
      // there, max(near, far) here). A term of a zero bound is exactly 0 or ∞ in both, so those edges are exact.
      // Twice the bounds.
      MIPNERF_CHECK_CLOSE("t_edges of degenerate ranges", dev, t_edges, [&](size_t i) {
        const size_t ray = i / (n + 1);
        const double near = r.near[ray], far = r.far[ray];
        return lindisp ? 2 * (16 * kUnitRoundoff * std::abs(t_edges[i]) + 6 * kUnitRoundoff * std::max(near, far))
                       : 2 * 12 * kUnitRoundoff * (near + far);
      });
      for (size_t ray = 0; ray < n_rays; ++ray) {
        const float* t = dev.data() + ray * (n + 1);
        INFO("near " << r.near[ray] << ", far " << r.far[ray]);
        // Edges run from near towards far: increasing, or decreasing when far < near.
        if (r.far[ray] < r.near[ray]) {
          REQUIRE(std::is_sorted(t, t + n + 1, std::greater<float>()));
        } else if (r.far[ray] > r.near[ray]) {
          REQUIRE(std::is_sorted(t, t + n + 1));
        }
        // The first and last edges are near and far themselves (1·near + 0·far, and the disparity guard's one term).
        if (!randomized) {
          CHECK(t[0] == r.near[ray]);
          CHECK(t[n] == r.far[ray]);
        }
      }
    }
  }
}

TEST_CASE("sample: jitter depends only on seed, step and ray, not on the chunking") {
  const size_t n = 64;
  const Ranges r = random_ranges(3000, 62);
  const SampleOptions options{false, true};
  const auto whole = run_stratified(options, r, n, {5, 9, 0});
  // The same rays in two chunks, the second keyed from ray 1000 on.
  const auto head = run_stratified(options, r, n, {5, 9, 0}, 0, 1000);
  const auto tail = run_stratified(options, r, n, {5, 9, 1000}, 1000);
  std::vector<float> chunked = head;
  chunked.insert(chunked.end(), tail.begin(), tail.end());
  CHECK(chunked == whole);
  CHECK(run_stratified(options, r, n, {5, 9, 0}) == whole);
  CHECK(run_stratified(options, r, n, {5, 10, 0}) != whole);
  CHECK(run_stratified(options, r, n, {6, 9, 0}) != whole);
  // Jitter fills each stratum: the fraction of each edge between its neighbours' midpoints is uniform, mean 1/2.
  double sum = 0;
  size_t count = 0;
  for (size_t ray = 0; ray < 3000; ++ray) {
    for (size_t k = 1; k < n; ++k) {
      const double step = (double(r.far[ray]) - r.near[ray]) / n;
      const double lower = r.near[ray] + (k - 0.5) * step;
      sum += (whole[ray * (n + 1) + k] - lower) / step;
      ++count;
    }
  }
  // 189,000 uniforms: standard error of the mean 0.29/sqrt(count) = 6.6e-4; 5 standard errors.
  CHECK(std::abs(sum / count - 0.5) < 5 * 0.29 / std::sqrt(double(count)));
}

TEST_CASE("sample: the sorted union of two edge sets matches std::merge exactly") {
  auto& ctx = test::test_context();
  std::mt19937 rng(63);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const size_t n_rays = 10000, len_a = 17, len_b = 33;
  std::vector<float> a, b;
  for (size_t ray = 0; ray < n_rays; ++ray) {
    std::vector<float> ra(len_a), rb(len_b);
    for (auto& x : ra) x = 2 + 4 * unit(rng);
    for (auto& x : rb) x = 2 + 4 * unit(rng);
    if (ray % 10 == 0) rb[3] = ra[5];  // ties between the sets
    std::sort(ra.begin(), ra.end());
    std::sort(rb.begin(), rb.end());
    a.insert(a.end(), ra.begin(), ra.end());
    b.insert(b.end(), rb.begin(), rb.end());
  }
  auto a_dev = test::upload(ctx, a, "t_a"), b_dev = test::upload(ctx, b, "t_b");
  auto out = test::filled(ctx, n_rays * (len_a + len_b), 7.0f, "t_out");
  ops::Sample(ctx, {}).merge({a_dev, b_dev, n_rays, len_a, len_b}, out);
  std::vector<double> expected;
  ref::sample_merge_fwd(test::to_double(a), test::to_double(b), expected, n_rays, len_a, len_b);
  MIPNERF_CHECK_CLOSE("t_out", out.download(ctx), expected, [](size_t) { return 0.0; });
}
