// What mipnerf-selftest records of each check it runs (one doctest test case of the suite), for its table and its
// JUnit file.
#pragma once

#include <string>
#include <vector>

namespace mipnerf::selftest {

struct CheckResult {
  std::string name;  // the suite's test case, e.g. "render: forward matches the reference ..."
  bool passed = false;
  bool skipped = false;  // support/skip.hpp: it could not run on this device or build
  std::string skip_reason;  // why, when skipped and known
  double seconds = 0.0;
  std::string worst_what;    // the compared quantity closest to its bound ("" when the check compares no arrays)
  double worst_ratio = 0.0;  // its max |device − reference| / bound: ≤ 1 passes
  double worst_error = 0.0;
  std::vector<std::string> failures;  // each failed assertion: where, what, and the worst element
};

// The results of the run so far, in order (filled by the "selftest" doctest reporter).
std::vector<CheckResult>& results();

}  // namespace mipnerf::selftest
