// Shared helpers of the MLP tests: random data, float ↔ double, and per-tensor comparisons against the double
// reference. NaN or Inf in a device value always fails. MLP_TEST_VERBOSE=1 prints every comparison's margin.
#pragma once

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "cl/buffer.hpp"
#include "cl/context.hpp"

namespace mipnerf::test {

inline std::vector<float> random_floats(size_t count, std::mt19937& rng, float lo = -1.0f, float hi = 1.0f) {
  std::uniform_real_distribution<float> dist(lo, hi);
  std::vector<float> values(count);
  for (auto& v : values) v = dist(rng);
  return values;
}

inline std::vector<double> as_double(const std::vector<float>& v) { return {v.begin(), v.end()}; }

inline ocl::DeviceArray<float> device_copy(ocl::Context& ctx, const std::vector<float>& values,
                                           const std::string& name) {
  ocl::DeviceArray<float> array(ctx, values.size(), name);
  array.upload(ctx, values);
  return array;
}

// Compares device[first … first+count) with reference[first … first+count): every device value finite and
// |device − reference| ≤ relative · max|reference over the range| + absolute. Reports the worst element.
inline void check_close(const std::vector<float>& device, const std::vector<double>& reference, size_t first,
                        size_t count, double relative, double absolute, const std::string& what) {
  REQUIRE(device.size() >= first + count);
  REQUIRE(reference.size() >= first + count);
  double scale = 0.0;
  for (size_t i = first; i < first + count; ++i) scale = std::max(scale, std::abs(reference[i]));
  const double tolerance = relative * scale + absolute;
  size_t non_finite = 0, worst = first;
  double worst_error = 0.0;
  for (size_t i = first; i < first + count; ++i) {
    if (!std::isfinite(device[i])) {
      ++non_finite;
      continue;
    }
    const double error = std::abs(static_cast<double>(device[i]) - reference[i]);
    if (error > worst_error) {
      worst_error = error;
      worst = i;
    }
  }
  INFO(what << ": worst |error| " << worst_error << " at " << worst - first << " (device " << device[worst]
            << ", reference " << reference[worst] << "), tolerance " << tolerance << " = " << relative << " · max "
            << scale << " + " << absolute);
  if (std::getenv("MLP_TEST_VERBOSE")) MESSAGE(what << ": worst " << worst_error << " / tol " << tolerance << " ratio " << worst_error / tolerance);
  CHECK(non_finite == 0);
  CHECK(worst_error <= tolerance);
}

}  // namespace mipnerf::test
