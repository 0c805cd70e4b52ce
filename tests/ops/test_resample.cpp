// Hierarchical resampling (kernels/resample.cl): against the reference (the official algorithm written as a
// search over the whole CDF), with a per-sample bound from the CDF's float error; all-zero weights, repeated
// edges and extreme weights stay sorted and finite; reproducibility across chunkings.
#include <doctest/doctest.h>

#include <algorithm>

#include "kernel_checks.hpp"
#include "ops/resample.hpp"
#include "ref/resample.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;
using test::kUnitRoundoff;

namespace {

struct Histograms {
  size_t n_rays = 0, n_samples = 0;
  std::vector<float> t_edges, weights;
};

// Sorted edges from 2..3 with random gaps (every 7th ray with some repeated edges); weights of five kinds:
// uniform random, sparse spikes, a smooth bump, all zero, and tiny (1e-30) values. `positive` keeps every weight
// > 0 (for NeRF's unpadded, unblurred setting, where zero-weight intervals make the inverse CDF jump).
Histograms random_histograms(size_t n_rays, size_t n, unsigned seed, bool positive) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Histograms h;
  h.n_rays = n_rays;
  h.n_samples = n;
  for (size_t ray = 0; ray < n_rays; ++ray) {
    float t = static_cast<float>(2 + unit(rng));
    for (size_t k = 0; k <= n; ++k) {
      h.t_edges.push_back(t);
      if (ray % 7 != 0 || k % 3 != 0) t += static_cast<float>(test::log_uniform(rng, 1e-3, 0.3));
    }
    const size_t kind = ray % 5, peak = rng() % n;
    for (size_t i = 0; i < n; ++i) {
      double w = 0;
      switch (kind) {
        case 0:
          w = unit(rng);
          break;
        case 1:
          w = unit(rng) < 0.1 ? unit(rng) : 0.0;
          break;
        case 2:
          w = std::exp(-0.5 * std::pow((double(i) - peak) / 2.0, 2));
          break;
        case 3:
          w = 0.0;
          break;
        default:
          w = 1e-30 * unit(rng);
          break;
      }
      if (positive) w = std::max(w, 1e-3 * (1 + unit(rng)));
      h.weights.push_back(static_cast<float>(w));
    }
  }
  return h;
}

// Resamples rays first .. first + count − 1 of `h` into m intervals (m = 0: as many as h has).
std::vector<float> run_device(const ResampleOptions& options, const Histograms& h, const RngKey& key, size_t first = 0,
                              size_t count = SIZE_MAX, size_t m = 0,
                              ops::ResampleItems items = ops::ResampleItems::device_default) {
  auto& ctx = test::test_context();
  count = std::min(count, h.n_rays - first);
  const size_t n = h.n_samples;
  const std::vector<float> t(h.t_edges.begin() + first * (n + 1), h.t_edges.begin() + (first + count) * (n + 1));
  const std::vector<float> w(h.weights.begin() + first * n, h.weights.begin() + (first + count) * n);
  auto t_dev = test::upload(ctx, t, "t_edges"), w_dev = test::upload(ctx, w, "weights");
  if (m == 0) m = n;
  auto out = test::filled(ctx, count * (m + 1), 7.0f, "t_new");
  ops::Resample stage(ctx, items);
  REQUIRE((items == ops::ResampleItems::device_default || stage.items() == items));
  stage.fwd(options, {t_dev, w_dev, count, n, m}, out, key);
  return out.download(ctx);
}

// Every row of m + 1 new edges sorted, finite and inside [t_0, t_N] of its coarse edges.
void check_sorted_inside(const std::vector<float>& t_new, const Histograms& h, size_t m) {
  const size_t n = h.n_samples;
  for (size_t ray = 0; ray < h.n_rays; ++ray) {
    const float* t = t_new.data() + ray * (m + 1);
    for (size_t j = 0; j <= m; ++j) REQUIRE(std::isfinite(t[j]));
    REQUIRE(std::is_sorted(t, t + m + 1));
    REQUIRE(t[0] >= h.t_edges[ray * (n + 1)]);
    REQUIRE(t[m] <= h.t_edges[ray * (n + 1) + n]);
  }
}

ResampleOptions mipnerf_options(bool randomized) { return {0.01f, true, randomized}; }
ResampleOptions nerf_options(bool randomized) { return {0.0f, false, randomized}; }

}  // namespace

TEST_CASE("resample: 16 rays walked together give each ray's own walk bit for bit, with a partial last item") {
  // 1,003 rays (103 under oclgrind: not a multiple of 16, so the last item has lanes past the rays, which must store
  // nothing), every weight kind of random_histograms, mip-NeRF's and NeRF's settings, M = N and M ≠ N.
  const size_t n_rays = test::batch_for_device(1000, 100) + 3;
  const RngKey key{78, 4, 300};
  for (bool nerf : {false, true}) {
    const Histograms h = random_histograms(n_rays, 48, 33, nerf);
    for (bool randomized : {false, true}) {
      for (size_t m : {size_t(48), size_t(21), size_t(96)}) {
        INFO(std::string(nerf ? "NeRF" : "mip-NeRF") << ", randomized " << randomized << ", " << m << " new intervals");
        const auto options = nerf ? nerf_options(randomized) : mipnerf_options(randomized);
        const auto per_ray = run_device(options, h, key, 0, SIZE_MAX, m, ops::ResampleItems::per_ray);
        CHECK(run_device(options, h, key, 0, SIZE_MAX, m, ops::ResampleItems::per_vector) == per_ray);
      }
    }
  }
}

TEST_CASE("resample: new edges match the CPU reference on 10,000 rays, mip-NeRF and NeRF settings") {
  const size_t n = 32;
  const RngKey key{77, 12, 4000};
  for (bool nerf : {false, true}) {
    const Histograms h = random_histograms(10000, n, 71, nerf);
    // mip-NeRF draws as many intervals as the coarse level has; the NeRF baseline its own count (here 48).
    const size_t m = nerf ? 48 : n;
    for (bool randomized : {false, true}) {
      INFO(std::string(nerf ? "NeRF" : "mip-NeRF") << ", randomized " << randomized);
      const auto options = nerf ? nerf_options(randomized) : mipnerf_options(randomized);
      const auto dev = run_device(options, h, key, 0, SIZE_MAX, m);
      std::vector<double> t_new;
      ref::resample_fwd(options, test::to_double(h.t_edges), test::to_double(h.weights), t_new, h.n_rays, n, m, key);
      // Tolerance. The kernel's CDF is a float running sum of N terms w_i/Σw: |Δcdf| ≤ (2N + 3)·u (the sum and each
      // quotient), and u_j is ≤ 3 roundings: |Δ(u − cdf)| ≤ (2N + 6)·u. The inverse CDF moves by that times its slope
      // (t_{k+1} − t_k)/(cdf_{k+1} − cdf_k), where the interval may be the reference's k or a neighbour; the final
      // interpolation rounds ≤ 4u of |t|. Twice the bound.
      std::vector<double> tol(t_new.size());
      for (size_t ray = 0; ray < h.n_rays; ++ray) {
        const auto w =
            test::to_double(std::vector<float>(h.weights.begin() + ray * n, h.weights.begin() + (ray + 1) * n));
        const auto cdf = ref::resample_cdf(options, w.data(), n);
        const float* t = h.t_edges.data() + ray * (n + 1);
        const auto slope = [&](size_t k) {
          return k < n && cdf[k + 1] > cdf[k] ? (double(t[k + 1]) - t[k]) / (cdf[k + 1] - cdf[k]) : 0.0;
        };
        for (size_t j = 0; j <= m; ++j) {
          const double value = t_new[ray * (m + 1) + j];
          size_t k = 0;
          while (k + 1 < n && double(t[k + 1]) <= value && cdf[k + 1] < 1) ++k;
          const double max_slope = std::max({slope(k), k > 0 ? slope(k - 1) : 0.0, slope(k + 1)});
          tol[ray * (m + 1) + j] = 2 * ((2 * n + 6) * kUnitRoundoff * max_slope + 4 * kUnitRoundoff * std::abs(value));
        }
      }
      MIPNERF_CHECK_CLOSE("t_new", dev, t_new, [&](size_t i) { return tol[i]; });
      check_sorted_inside(dev, h, m);
    }
  }
}

TEST_CASE("resample: all-zero weights, repeated edges and extreme weights stay sorted and finite") {
  const size_t n = 16;
  Histograms h;
  h.n_samples = n;
  const auto add = [&](std::vector<float> t, std::vector<float> w) {
    h.t_edges.insert(h.t_edges.end(), t.begin(), t.end());
    h.weights.insert(h.weights.end(), w.begin(), w.end());
    ++h.n_rays;
  };
  std::vector<float> uniform_t(n + 1), repeated_t(n + 1), w_zero(n, 0.0f), w_spiky(n, 0.0f), w_huge(n), w_tiny(n);
  for (size_t k = 0; k <= n; ++k) {
    uniform_t[k] = 2.0f + 0.25f * k;
    repeated_t[k] = 2.0f + static_cast<float>(k / 4);  // 2,2,2,2,3,3,3,3,...
  }
  w_spiky[3] = 1.0f;
  for (size_t i = 0; i < n; ++i) {
    w_huge[i] = i % 2 ? 1e30f : 1e-30f;
    w_tiny[i] = 1e-38f;  // below the 1e-5 floor: treated as (nearly) uniform
  }
  add(uniform_t, w_zero);                         // 0: all-zero weights
  add(repeated_t, w_zero);                        // 1: all-zero weights on repeated edges
  add(repeated_t, w_spiky);                       // 2: one spike on repeated edges
  add(std::vector<float>(n + 1, 5.0f), w_spiky);  // 3: every edge equal
  add(uniform_t, w_huge);                         // 4: weights of 1e30 and 1e-30 (Σ near float's max is avoided)
  add(uniform_t, w_tiny);                         // 5: denormal-scale weights
  for (bool nerf : {false, true}) {
    for (bool randomized : {false, true}) {
      INFO(std::string(nerf ? "NeRF" : "mip-NeRF") << ", randomized " << randomized);
      const auto options = nerf ? nerf_options(randomized) : mipnerf_options(randomized);
      const auto dev = run_device(options, h, {1, 2, 3});
      check_sorted_inside(dev, h, n);
      check_sorted_inside(run_device(options, h, {1, 2, 3}, 0, SIZE_MAX, 3 * n), h, 3 * n);
      check_sorted_inside(run_device(options, h, {1, 2, 3}, 0, SIZE_MAX, 1), h, 1);
      // Every edge equal: every sample is that value.
      for (size_t j = 0; j <= n; ++j) CHECK(dev[3 * (n + 1) + j] == 5.0f);
      if (!randomized) {
        // All-zero weights with the 1e-5 floor give the uniform PDF: deterministic samples at the linspace u,
        // t = 2 + 4·u_j with u_j = j·(1 − ε)/N (float rounding ≤ 8 roundoffs of t).
        for (size_t j = 0; j <= n; ++j) {
          const double u = std::min(j * (1.0 - 1.1920929e-07) / n, 1.0 - 1.1920929e-07);
          CHECK(std::abs(dev[j] - (2.0 + 4.0 * u)) <= 8 * kUnitRoundoff * 6.0);
        }
      }
    }
  }
}

TEST_CASE("resample: jitter depends only on seed, step and ray, not on the chunking") {
  const size_t n = 24;
  const Histograms h = random_histograms(2000, n, 72, false);
  const auto options = mipnerf_options(true);
  const auto whole = run_device(options, h, {8, 1, 0});
  auto chunked = run_device(options, h, {8, 1, 0}, 0, 700);
  const auto tail = run_device(options, h, {8, 1, 700}, 700);
  chunked.insert(chunked.end(), tail.begin(), tail.end());
  CHECK(chunked == whole);
  CHECK(run_device(options, h, {8, 2, 0}) != whole);
  // Asking for no new intervals is refused with a message saying what to pass.
  auto& ctx = test::test_context();
  ocl::DeviceArray<float> t(ctx, 2 * (n + 1), "t"), w(ctx, 2 * n, "w"), out(ctx, 2 * (n + 1), "out");
  CHECK_THROWS_WITH_AS(ops::Resample(ctx).fwd(options, {t, w, 2, n, 0}, out), doctest::Contains("new_samples"), Error);
  // The deterministic setting ignores the key.
  CHECK(run_device(mipnerf_options(false), h, {8, 1, 0}) == run_device(mipnerf_options(false), h, {9, 3, 0}));
}
