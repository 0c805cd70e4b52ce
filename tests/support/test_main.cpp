// doctest's main for every test executable: run the tests, then release the shared test context before exit; a
// passing run in which a test was skipped (support/skip.hpp) exits with CTest's skip code.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include "support/skip.hpp"
#include "support/test_context.hpp"

int main(int argc, char** argv) {
  doctest::Context context(argc, argv);
  const int result = context.run();
  mipnerf::test::release_test_context();  // before static destructors (see test_context.hpp)
  if (result == 0 && mipnerf::test::any_test_skipped()) return mipnerf::test::kSkipExitCode;
  return result;
}
