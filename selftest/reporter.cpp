// The doctest reporter of mipnerf-selftest: one CheckResult per test case, with the worst comparison against the
// reference (tests/support/comparison_log) and every failed assertion with its context.
#include "reporter.hpp"

#include <doctest/doctest.h>

#include <sstream>

#include "support/comparison_log.hpp"
#include "support/skip.hpp"

namespace mipnerf::selftest {

std::vector<CheckResult>& results() {
  static std::vector<CheckResult> all;
  return all;
}

namespace {

class SelftestReporter : public doctest::IReporter {
 public:
  explicit SelftestReporter(const doctest::ContextOptions&) {}

  void report_query(const doctest::QueryData&) override {}
  void test_run_start() override {}
  void test_run_end(const doctest::TestRunStats&) override {}
  void test_case_start(const doctest::TestCaseData& data) override {
    current_ = CheckResult{};
    current_.name = data.m_name;
    skips_before_ = test::skip_count();
    test::reset_comparisons();
  }
  void test_case_reenter(const doctest::TestCaseData&) override {}
  void test_case_end(const doctest::CurrentTestCaseStats& stats) override {
    current_.passed = stats.testCaseSuccess;
    current_.skipped = current_.passed && test::skip_count() > skips_before_;
    current_.seconds = stats.seconds;
    const auto& worst = test::worst_comparison();
    if (worst.count > 0) {
      current_.worst_what = worst.what;
      current_.worst_ratio = worst.ratio;
      current_.worst_error = worst.error;
    }
    results().push_back(current_);
  }
  void test_case_exception(const doctest::TestCaseException& e) override {
    current_.failures.push_back(std::string(e.is_crash ? "crashed: " : "threw: ") + e.error_string.c_str());
  }
  void subcase_start(const doctest::SubcaseSignature&) override {}
  void subcase_end() override {}
  void log_assert(const doctest::AssertData& data) override {
    if (!data.m_failed) return;
    std::ostringstream out;
    out << file_name(data.m_file) << ":" << data.m_line << ": " << data.m_expr;
    if (data.m_decomp.size() > 0) out << " (" << data.m_decomp.c_str() << ")";
    if (data.m_threw) out << " threw: " << data.m_exception.c_str();
    for (int i = 0; i < doctest::IReporter::get_num_stringified_contexts(); ++i) {
      out << "; " << doctest::IReporter::get_stringified_contexts()[i].c_str();
    }
    current_.failures.push_back(out.str());
  }
  void log_message(const doctest::MessageData&) override {}
  void test_case_skipped(const doctest::TestCaseData&) override {}

 private:
  static std::string file_name(const char* path) {
    const std::string p(path);
    const auto slash = p.rfind('/');
    return slash == std::string::npos ? p : p.substr(slash + 1);
  }

  CheckResult current_;
  size_t skips_before_ = 0;
};

REGISTER_REPORTER("selftest", 1, SelftestReporter);

}  // namespace
}  // namespace mipnerf::selftest
