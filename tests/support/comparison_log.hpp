// The worst element comparison of the running test case (MIPNERF_CHECK_CLOSE records every one), for reports that
// show how close a device came to its bound: mipnerf-selftest's table.
#pragma once

#include <cstddef>
#include <string>

namespace mipnerf::test {

struct WorstComparison {
  std::string what;    // the compared quantity with the worst ratio, e.g. "radii"
  double ratio = 0.0;  // its max |device − reference| / tolerance (≤ 1 passes)
  double error = 0.0;  // that element's |device − reference|
  size_t count = 0;    // comparisons recorded since the last reset
};

// Records one comparison; keeps the worst.
void record_comparison(const std::string& what, double ratio, double error);
const WorstComparison& worst_comparison();
void reset_comparisons();

}  // namespace mipnerf::test
