// Helpers of the tests/official suite: the fixtures the official google/mipnerf code wrote (make_vectors.py), their
// arrays as flat vectors, and element-wise agreement of our values with the official ones under a per-element bound.
// NaN or Inf in our values always fails.
#pragma once

#include <doctest/doctest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "io/json.hpp"

namespace mipnerf::official {

// The commit of github:google/mipnerf the fixtures were computed from (make_vectors.py writes it into each).
inline constexpr const char* kOfficialCommit = "84c969e0a623edd183b75693aed72a7e7c22902d";

// Unit roundoff of float32 (half an ulp of 1): the relative error of one correctly rounded float operation.
constexpr double kU = 5.9604644775390625e-08;  // 2^-24

// tests/official/fixtures, found beside this file (CMake compiles sources by absolute path); MIPNERF_OFFICIAL_FIXTURES
// overrides it.
inline std::filesystem::path fixture_dir() {
  if (const char* env = std::getenv("MIPNERF_OFFICIAL_FIXTURES")) return env;
  return std::filesystem::path(__FILE__).parent_path() / "fixtures";
}

// The commits of the other official repositories whose functions wrote fixtures (each fixture records its own under
// "zipnerf_commit" or "multinerf_commit").
inline constexpr const char* kZipnerfCommit = "8e6d57e3aee34235faf3ef99decca0994efe66c9";    // jonbarron/camp_zipnerf
inline constexpr const char* kMultinerfCommit = "5b4d4f64608ec8077222c52fdf814d40acc10bc1";  // google-research/multinerf

// One fixture, checked to record `commit` under `commit_key`.
inline io::Json fixture_from(const std::string& name, const std::string& commit_key, const std::string& commit) {
  const auto path = fixture_dir() / name;
  INFO("fixture " << path.string() << " (set MIPNERF_OFFICIAL_FIXTURES if the sources moved)");
  REQUIRE(std::filesystem::is_regular_file(path));
  io::Json json = io::read_json(path.string());
  REQUIRE(json.at(commit_key).get<std::string>() == commit);
  return json;
}

// One fixture of google/mipnerf's, checked to come from kOfficialCommit.
inline io::Json fixture(const std::string& name) { return fixture_from(name, "official_commit", kOfficialCommit); }

// One fixture of camp_zipnerf's (kZipnerfCommit) or multinerf's (kMultinerfCommit).
inline io::Json zipnerf_fixture(const std::string& name) { return fixture_from(name, "zipnerf_commit", kZipnerfCommit); }
inline io::Json multinerf_fixture(const std::string& name) {
  return fixture_from(name, "multinerf_commit", kMultinerfCommit);
}

namespace detail {
inline void flatten(const io::Json& value, std::vector<double>& out, std::vector<size_t>& shape, size_t depth) {
  if (!value.is_array()) {
    REQUIRE(value.is_number());
    REQUIRE(depth == shape.size());
    out.push_back(value.get<double>());
    return;
  }
  if (depth == shape.size()) shape.push_back(value.size());
  REQUIRE(shape[depth] == value.size());  // rectangular
  for (const auto& item : value) flatten(item, out, shape, depth + 1);
}
}  // namespace detail

// A nested JSON array as one row-major vector; `shape` (when given) must be its shape.
inline std::vector<double> flat(const io::Json& value, const std::vector<size_t>& shape = {}) {
  std::vector<double> out;
  std::vector<size_t> found;
  detail::flatten(value, out, found, 0);
  if (!shape.empty()) REQUIRE(found == shape);
  return out;
}

inline std::vector<float> as_float(const std::vector<double>& v) { return {v.begin(), v.end()}; }

template <typename T>
ocl::DeviceArray<T> upload(ocl::Context& ctx, const std::vector<T>& values, const std::string& name) {
  ocl::DeviceArray<T> array(ctx, values.size(), name);
  array.upload(ctx, values);
  return array;
}

// How our values agree with the official ones: the worst element relative to its bound.
struct Agreement {
  size_t count = 0;
  size_t failures = 0;    // elements beyond their bound (non-finite ones included)
  size_t non_finite = 0;  // NaN or Inf in our values
  size_t worst = 0;       // index of the largest |ours − official| / bound
  double worst_ratio = 0.0;
  double worst_error = 0.0;
  double ours = 0.0, theirs = 0.0;
};

template <typename T>
Agreement agree(const std::vector<T>& ours, const std::vector<double>& theirs,
                const std::function<double(size_t)>& bound) {
  Agreement a;
  a.count = theirs.size();
  for (size_t i = 0; i < theirs.size(); ++i) {
    const double o = static_cast<double>(ours[i]), t = theirs[i];
    double ratio;
    if (!std::isfinite(o)) {
      ++a.non_finite;
      ratio = INFINITY;
    } else {
      const double error = std::abs(o - t), b = bound(i);
      ratio = b > 0 ? error / b : (error > 0 ? INFINITY : 0.0);
    }
    if (ratio > 1.0) ++a.failures;
    if (ratio > a.worst_ratio || i == 0) {
      a.worst_ratio = ratio;
      a.worst = i;
      a.worst_error = std::abs(o - t);
      a.ours = o;
      a.theirs = t;
    }
  }
  return a;
}

inline std::function<double(size_t)> constant_bound(double b) {
  return [b](size_t) { return b; };
}

}  // namespace mipnerf::official

// CHECKs that our values agree with the official ones, element by element, within the bound (the last argument: a
// function of the element index); names the worst element.
#define OFFICIAL_CHECK_AGREES(WHAT, OURS, THEIRS, ...)                                                                \
  do {                                                                                                                \
    REQUIRE((OURS).size() >= (THEIRS).size());                                                                        \
    const auto agreement_ = ::mipnerf::official::agree((OURS), (THEIRS), (__VA_ARGS__));                              \
    INFO((WHAT) << ": worst element " << agreement_.worst << " of " << agreement_.count << ": ours "                  \
                << agreement_.ours << ", official " << agreement_.theirs << ", error " << agreement_.worst_error      \
                << " = " << agreement_.worst_ratio << " x bound; " << agreement_.failures << " beyond the bound, "    \
                << agreement_.non_finite << " non-finite");                                                           \
    if (std::getenv("MIPNERF_TEST_VERBOSE")) {                                                                        \
      MESSAGE((WHAT) << ": worst error " << agreement_.worst_error << " = " << agreement_.worst_ratio << " x bound"); \
    }                                                                                                                 \
    CHECK(agreement_.non_finite == 0);                                                                                \
    CHECK(agreement_.failures == 0);                                                                                  \
  } while (0)

// CHECKs that our values do NOT agree: the worst element is beyond MARGIN times its bound (the last argument) or not
// finite, so a changed convention cannot pass for rounding.
#define OFFICIAL_CHECK_DISAGREES(WHAT, OURS, THEIRS, MARGIN, ...)                                                      \
  do {                                                                                                                 \
    REQUIRE((OURS).size() >= (THEIRS).size());                                                                         \
    const auto agreement_ = ::mipnerf::official::agree((OURS), (THEIRS), (__VA_ARGS__));                               \
    INFO((WHAT) << " (must not match): worst element " << agreement_.worst << ": ours " << agreement_.ours             \
                << ", official " << agreement_.theirs << " = " << agreement_.worst_ratio << " x bound");               \
    if (std::getenv("MIPNERF_TEST_VERBOSE")) {                                                                         \
      MESSAGE((WHAT) << " (must not match): worst " << agreement_.worst_ratio << " x bound, " << agreement_.non_finite \
                     << " non-finite");                                                                                \
    }                                                                                                                  \
    CHECK(agreement_.worst_ratio > (MARGIN));                                                                          \
  } while (0)
