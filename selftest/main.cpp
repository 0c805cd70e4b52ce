// mipnerf-selftest: proof on the user's own device. Runs the suite's own checks of every kernel stage (each against
// the double-precision CPU reference, at the suite's bounds), of the MLP on every GEMM backend the device can run, of
// whole training steps against the reference graph, and a few training steps against another CPU device when there is
// one; prints a table (check, worst error / bound, pass) and exits non-zero on any failure. The product executable
// does not link the reference; this one does, so a user can run it without building or running the test suite.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>

#include "cl/context.hpp"
#include "core/error.hpp"
#include "cross_device.hpp"
#include "reporter.hpp"
#include "support/temp_scene.hpp"
#include "support/test_context.hpp"

namespace {

using mipnerf::selftest::CheckResult;

// The suite's test cases the self-test runs: the ray-math stages and their specialisations (tests/ops), the products
// (tests/gemm), the MLP's kernels and Adam (tests/mlp), whole training steps (tests/graph), and the cross-device steps
// (selftest/).
// --quick keeps what fits a simulator (oclgrind runs kernels thousands of times slower): every specialisation of every
// ray-math stage, the MLP's element-wise kernels, Adam and the small networks (the training step and CLBlast's larger
// products take minutes there).
const char* kFullFilter = "*";
const char* kQuickFilter = "specialisations:*,mlp kernels:*,adam: device steps*,mlp device: small network*";
// The check only the self-test has (selftest/test_cross_device.cpp); --quick --cross-device adds it.
const char* kCrossDevice = "training: three steps agree with another CPU device";

std::string ratio_text(const CheckResult& r) {
  if (r.worst_what.empty()) return "-";
  char text[96];
  std::snprintf(text, sizeof(text), "%.3g (%s)", r.worst_ratio, r.worst_what.c_str());
  return text;
}

std::string verdict(const CheckResult& r) { return !r.passed ? "FAIL" : r.skipped ? "skipped" : "pass"; }

void print_table(const std::vector<CheckResult>& results) {
  std::cout << "\n| check | worst error / bound | seconds | result |\n|---|---|---:|---|\n";
  for (const auto& r : results) {
    char seconds[32];
    std::snprintf(seconds, sizeof(seconds), "%.2f", r.seconds);
    std::cout << "| " << r.name << " | " << ratio_text(r) << " | " << seconds << " | " << verdict(r) << " |\n";
  }
  for (const auto& r : results) {
    for (const auto& failure : r.failures) std::cout << "FAIL " << r.name << ": " << failure << "\n";
  }
}

std::string xml_escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// A JUnit file of the checks, as CTest writes one: scripts/stage_table.py counts it like a CTest stage.
void write_junit(const std::string& path, const std::vector<CheckResult>& results) {
  std::ofstream out(path);
  if (!out) throw mipnerf::Error(path + ": cannot write the JUnit file");
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuite name=\"mipnerf-selftest\" tests=\"" << results.size()
      << "\">\n";
  for (const auto& r : results) {
    out << "  <testcase name=\"" << xml_escape(r.name) << "\" time=\"" << r.seconds << "\"";
    if (r.passed && !r.skipped) {
      out << "/>\n";
      continue;
    }
    out << ">\n";
    if (!r.passed) {
      std::string message;
      for (const auto& f : r.failures) message += f + "\n";
      out << "    <failure message=\"" << xml_escape(message) << "\"/>\n";
    } else {
      out << "    <skipped message=\"" << xml_escape(r.skip_reason.empty() ? "skipped" : r.skip_reason) << "\"/>\n";
    }
    out << "  </testcase>\n";
  }
  out << "</testsuite>\n";
}

}  // namespace

int main(int argc, char** argv) {
  using namespace mipnerf;
  CLI::App app{
      "mipnerf-selftest: checks every kernel stage, the MLP and training steps on an OpenCL device against "
      "the double-precision CPU reference, at the test suite's bounds"};
  std::string device, expect_platform, junit, injected_option;
  bool quick = false, cross_device = false;
  app.add_option("--device", device,
                 "OpenCL device, as mipnerf-cl --device takes it (default: $MIPNERF_DEVICE, "
                 "else the first GPU, else the first CPU)")
      ->envname("MIPNERF_DEVICE");
  app.add_flag("--quick", quick,
               "Only the checks that fit a slow device or simulator (every specialisation of every "
               "stage, the MLP kernels, Adam, small networks)");
  app.add_flag("--cross-device", cross_device,
               "With --quick: also train three steps here and on another CPU device and compare them (the check the "
               "full list has that the test suite does not)");
  app.add_option("--expect-platform", expect_platform,
                 "Fail unless the device is on this OpenCL platform (the test command's stages)");
  app.add_option("--junit", junit, "Also write the results as a JUnit file");
  app.add_option("--inject-build-option", injected_option,
                 "Test-only: build every kernel with this extra compiler option (e.g. -cl-fast-relaxed-math), "
                 "standing in for a driver that computes carelessly; the self-test must then fail")
      ->group("");
  CLI11_PARSE(app, argc, argv);

  // The suite's test context takes its device from these (tests/support/test_context.hpp).
  setenv("MIPNERF_TEST_DEVICE", device.c_str(), 1);
  if (!expect_platform.empty()) setenv("MIPNERF_TEST_PLATFORM", expect_platform.c_str(), 1);
  const auto started = std::chrono::steady_clock::now();
  try {
    auto& ctx = test::test_context();
    if (!injected_option.empty()) {
      ocl::BuildOptions fault;
      if (injected_option.rfind("-D", 0) == 0) {
        const auto eq = injected_option.find('=');
        fault.define(injected_option.substr(2, eq == std::string::npos ? std::string::npos : eq - 2),
                     eq == std::string::npos ? "1" : injected_option.substr(eq + 1));
      } else {
        fault.flag(injected_option);
      }
      ctx.add_base_options(fault);
      std::cout << "selftest: every kernel built with " << fault.str()
                << " (--inject-build-option): checks must fail\n";
    }
    const auto& d = ctx.device_info();
    std::cout << "selftest: device [" << d.index << "] " << d.name << " (" << d.type_name() << "), platform '"
              << d.platform_name << "', driver " << d.driver_version << ", " << d.opencl_c_version << "\n";
  } catch (const std::exception& e) {
    std::cerr << "mipnerf-selftest: error: " << e.what() << "\n";
    return 2;
  }

  doctest::Context checks;
  checks.setOption("reporters", "selftest");
  const std::string quick_filter = std::string(kQuickFilter) + (cross_device ? "," + std::string(kCrossDevice) : "");
  checks.setOption("test-case", quick ? quick_filter.c_str() : kFullFilter);
  // Training against another CPU device needs one: without it the check is left out, and said so (not passed): a
  // row of its own, skipped, in the table and the JUnit file.
  std::string cross_device_skipped;
  if ((!quick || cross_device) && !selftest::other_cpu_device(test::test_context().device_info())) {
    checks.setOption("test-case-exclude", kCrossDevice);
    cross_device_skipped = "no other CPU device here, so training steps are compared with the reference graph only "
                           "(the graph checks), not with a second device";
    std::cout << "selftest: " << cross_device_skipped << "\n";
  }
  checks.setOption("no-breaks", true);
  const int status = checks.run();
  test::release_test_context();
  test::remove_process_temp_entries();  // the checks' scenes in the system temp folder: a user's machine keeps none

  if (!cross_device_skipped.empty()) {
    CheckResult row;
    row.name = kCrossDevice;
    row.passed = true;
    row.skipped = true;
    row.skip_reason = cross_device_skipped;
    selftest::results().push_back(row);
  }
  const auto& results = selftest::results();
  print_table(results);
  if (!junit.empty()) write_junit(junit, results);
  size_t failed = 0, skipped = 0;
  for (const auto& r : results) {
    failed += r.passed ? 0 : 1;
    skipped += r.passed && r.skipped ? 1 : 0;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  std::printf("\nselftest: %zu checks, %zu failed, %zu skipped, %.1f s\n", results.size(), failed, skipped, seconds);
  if (failed > 0 || status != 0 || results.empty()) {
    std::cout << "selftest: FAILED. This device computes something else than the reference: please report it in "
                 "mipnerf-cl's issue tracker with this whole output and that of `mipnerf-cl devices` (device, "
                 "driver and platform versions), and train on another device meanwhile.\n";
    return 1;
  }
  std::cout << "selftest: every check passed on this device\n";
  return 0;
}
