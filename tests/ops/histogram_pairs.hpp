// Batches of histogram pairs for the interlevel losses' tests (tests/ops/test_interlevel.cpp, spline;
// tests/ops/test_interlevel_outer.cpp, outer): per ray a NeRF histogram (c [n+1] sorted, w [n]) and a proposal round's
// (cp [m+1], wp [m]).
#pragma once

#include <doctest/doctest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace mipnerf::test {

struct HistogramPairs {
  std::vector<float> c, w, cp, wp;
  size_t n_rays = 0, n = 16, m = 12;
};

// `count` sorted edges from lo to hi (both included), the others uniform between.
inline std::vector<float> random_sorted_edges(std::mt19937& rng, size_t count, float lo, float hi) {
  std::uniform_real_distribution<float> u(lo, hi);
  std::vector<float> e(count);
  e.front() = lo;
  e.back() = hi;
  for (size_t i = 1; i + 1 < count; ++i) e[i] = u(rng);
  std::sort(e.begin(), e.end());
  return e;
}

// `count` weights (products of two uniforms: many small ones) summing to `total`.
inline std::vector<float> random_weights(std::mt19937& rng, size_t count, float total) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<float> w(count);
  float sum = 0;
  for (auto& x : w) sum += (x = u(rng) * u(rng));
  for (auto& x : w) x = x * total / sum;
  return w;
}

inline void add_histogram_pair(HistogramPairs& b, const std::vector<float>& c, const std::vector<float>& w,
                               const std::vector<float>& cp, const std::vector<float>& wp) {
  REQUIRE(c.size() == b.n + 1);
  REQUIRE(w.size() == b.n);
  REQUIRE(cp.size() == b.m + 1);
  REQUIRE(wp.size() == b.m);
  b.c.insert(b.c.end(), c.begin(), c.end());
  b.w.insert(b.w.end(), w.begin(), w.end());
  b.cp.insert(b.cp.end(), cp.begin(), cp.end());
  b.wp.insert(b.wp.end(), wp.begin(), wp.end());
  ++b.n_rays;
}

}  // namespace mipnerf::test
