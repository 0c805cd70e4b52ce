// doctest's main for every test executable: run the tests, then release the shared test context before exit; a
// passing run in which a test was skipped (support/skip.hpp) exits with CTest's skip code, and a run that matched no
// test case fails: doctest exits 0 when its filter selects nothing, so a CTest entry whose name no longer matches its
// test (a renamed case, a name that CTest split at a ';', an oclgrind entry's stale filter) would pass unchecked.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <iostream>

#include "support/skip.hpp"
#include "support/temp_scene.hpp"
#include "support/test_context.hpp"

namespace {

// Counts the test cases that started (doctest's listeners see every event the reporters do).
struct CaseCounter : doctest::IReporter {
  static int& started() {
    static int count = 0;
    return count;
  }
  explicit CaseCounter(const doctest::ContextOptions&) {}
  void report_query(const doctest::QueryData&) override {}
  void test_run_start() override {}
  void test_run_end(const doctest::TestRunStats&) override {}
  void test_case_start(const doctest::TestCaseData&) override { ++started(); }
  void test_case_reenter(const doctest::TestCaseData&) override {}
  void test_case_end(const doctest::CurrentTestCaseStats&) override {}
  void test_case_exception(const doctest::TestCaseException&) override {}
  void subcase_start(const doctest::SubcaseSignature&) override {}
  void subcase_end() override {}
  void log_assert(const doctest::AssertData&) override {}
  void log_message(const doctest::MessageData&) override {}
  void test_case_skipped(const doctest::TestCaseData&) override {}
};
REGISTER_LISTENER("case_counter", 1, CaseCounter);

}  // namespace

int main(int argc, char** argv) {
  doctest::Context context(argc, argv);
  const int result = context.run();
  mipnerf::test::release_test_context();  // before static destructors (see test_context.hpp)
  if (context.shouldExit()) return result;  // --list-test-cases, --help, …: no test was meant to run
  if (CaseCounter::started() == 0) {
    std::cerr << "tests: no test case matched the filters given (" << argv[0]
              << "): a test that runs nothing must not pass\n";
    return 1;
  }
  if (result == 0) {
    mipnerf::test::remove_process_temp_entries();
  } else {
    for (const auto& entry : mipnerf::test::process_temp_entries()) {
      std::cerr << "tests: kept for a look: " << entry.string() << "\n";
    }
  }
  if (result == 0 && mipnerf::test::any_test_skipped()) return mipnerf::test::kSkipExitCode;
  return result;
}
