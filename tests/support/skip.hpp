// Skipping a test that cannot run here (a missing optional dependency, a device without a capability): reported as
// skipped, never as passed, and a failure under CI, where every dependency is installed and every test must run.
#pragma once

#include <cstddef>
#include <string>

namespace mipnerf::test {

// Call from a test case, then return from it. Under CI=true this fails the test ("required in CI: <reason>");
// otherwise it prints "skipped: <reason>" and marks the process, whose exit status becomes kSkipExitCode when
// nothing failed (CTest's SKIP_RETURN_CODE for every doctest test: tests/CMakeLists.txt).
void skip_test(const std::string& reason);

// Whether skip_test ran in this process (test_main turns a passing run into kSkipExitCode), and how often.
bool any_test_skipped();
size_t skip_count();

inline constexpr int kSkipExitCode = 77;

}  // namespace mipnerf::test
