// Shared helpers of the ray-math kernel tests: uploads, float ↔ double, and element-wise comparisons against the
// double reference with a per-element tolerance. NaN or Inf in a device result always fails.
#pragma once

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "ops/ray_bundle.hpp"
#include "support/comparison_log.hpp"

namespace mipnerf::test {

// Unit roundoff of float32 (half an ulp of 1): the relative error of one correctly rounded operation.
constexpr double kUnitRoundoff = 5.9604644775390625e-08;  // 2^-24

inline std::vector<double> to_double(const std::vector<float>& v) { return {v.begin(), v.end()}; }

inline std::vector<float> to_float(const std::vector<double>& v) {
  std::vector<float> out(v.size());
  for (size_t i = 0; i < v.size(); ++i) out[i] = static_cast<float>(v[i]);
  return out;
}

template <typename T>
ocl::DeviceArray<T> upload(ocl::Context& ctx, const std::vector<T>& values, const std::string& name) {
  ocl::DeviceArray<T> array(ctx, values.size(), name);
  array.upload(ctx, values);
  return array;
}

// An array of `count` elements, every one set to `value` (a sentinel that shows what a kernel did not write).
inline ocl::DeviceArray<float> filled(ocl::Context& ctx, size_t count, float value, const std::string& name) {
  ocl::DeviceArray<float> array(ctx, count, name);
  array.upload(ctx, std::vector<float>(count, value));
  return array;
}

// A bundle of `n_rays` rays, every element of every array set to `value` (a sentinel, as filled()).
inline ops::RayBundle filled_rays(ocl::Context& ctx, size_t n_rays, float value) {
  ops::RayBundle rays(ctx, n_rays);
  for (auto* array : {&rays.origins, &rays.directions, &rays.viewdirs, &rays.radii, &rays.near, &rays.far,
                      &rays.lossmult}) {
    array->upload(ctx, std::vector<float>(array->size(), value));
  }
  return rays;
}

// Compares device[i] with reference[i] under tolerance(i) and reports the worst element. Every device value
// must be finite (unless the reference is NaN, where the device must be NaN too).
struct Comparison {
  size_t failures = 0;
  size_t non_finite = 0;
  size_t worst_index = 0;
  double worst_ratio = 0.0;  // max |device − reference| / tolerance
  double worst_error = 0.0;
};

inline Comparison compare(const std::vector<float>& device, const std::vector<double>& reference,
                          const std::function<double(size_t)>& tolerance) {
  Comparison c;
  for (size_t i = 0; i < reference.size(); ++i) {
    const double d = device[i], r = reference[i];
    if (std::isnan(r)) {
      if (!std::isnan(d)) ++c.failures;
      continue;
    }
    if (!std::isfinite(d)) {
      ++c.non_finite;
      ++c.failures;
      continue;
    }
    const double error = std::abs(d - r), tol = tolerance(i);
    const double ratio = tol > 0 ? error / tol : (error > 0 ? INFINITY : 0.0);
    if (ratio > 1.0) ++c.failures;
    if (ratio > c.worst_ratio) {
      c.worst_ratio = ratio;
      c.worst_index = i;
      c.worst_error = error;
    }
  }
  return c;
}

// CHECKs that every element is within tolerance; prints the worst element either way (INFO on failure).
#define MIPNERF_CHECK_CLOSE(what, device, reference, ...)                                                            \
  do {                                                                                                               \
    REQUIRE((device).size() >= (reference).size());                                                                  \
    const auto cmp_ = ::mipnerf::test::compare((device), (reference), (__VA_ARGS__));                                \
    INFO(what << ": worst element " << cmp_.worst_index << " device " << (device)[cmp_.worst_index] << " reference " \
              << (reference)[cmp_.worst_index] << " error " << cmp_.worst_error << " = " << cmp_.worst_ratio         \
              << " x tolerance; " << cmp_.non_finite << " non-finite");                                              \
    if (std::getenv("MIPNERF_TEST_VERBOSE")) {                                                                       \
      MESSAGE(what << ": worst error " << cmp_.worst_error << " = " << cmp_.worst_ratio << " x tolerance");          \
    }                                                                                                                \
    std::ostringstream what_;                                                                                        \
    what_ << what;                                                                                                   \
    ::mipnerf::test::record_comparison(what_.str(), cmp_.non_finite ? INFINITY : cmp_.worst_ratio,                   \
                                       cmp_.worst_error);                                                            \
    CHECK(cmp_.non_finite == 0);                                                                                     \
    CHECK(cmp_.failures == 0);                                                                                       \
  } while (0)

inline bool all_finite(const std::vector<float>& v) {
  for (float x : v) {
    if (!std::isfinite(x)) return false;
  }
  return true;
}

inline double log_uniform(std::mt19937& rng, double lo, double hi) {
  std::uniform_real_distribution<double> dist(std::log(lo), std::log(hi));
  return std::exp(dist(rng));
}

// The largest |central difference − analytic gradient| over every `stride`-th value of `values` (step h, each value
// put back after), and the largest |gradient| seen, for a scalar objective of all the values.
struct DifferenceCheck {
  double worst = 0;
  double largest_gradient = 0;
};
inline DifferenceCheck central_differences(std::vector<double>& values, const std::vector<double>& gradient,
                                           const std::function<double(const std::vector<double>&)>& objective,
                                           size_t stride = 1, double h = 1e-3) {
  DifferenceCheck out;
  for (size_t e = 0; e < values.size(); e += stride) {
    const double kept = values[e];
    values[e] = kept + h;
    const double up = objective(values);
    values[e] = kept - h;
    const double down = objective(values);
    values[e] = kept;
    out.worst = std::max(out.worst, std::abs((up - down) / (2 * h) - gradient[e]));
    out.largest_gradient = std::max(out.largest_gradient, std::abs(gradient[e]));
  }
  return out;
}

// Σ weights[i] · outputs[i]: the objective whose gradient a backward given `weights` as its upstream gradient computes.
inline double weighted_sum(const std::vector<double>& weights, const std::vector<double>& outputs) {
  double sum = 0;
  for (size_t i = 0; i < outputs.size(); ++i) sum += weights[i] * outputs[i];
  return sum;
}

}  // namespace mipnerf::test
