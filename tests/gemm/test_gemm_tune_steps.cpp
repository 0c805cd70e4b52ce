// The GEMM tune's steps on the test device (mlp/gemm_tune_steps.hpp), run in-process: a candidate timed and
// checked through the real routine, the error ratio that decides "correct", and the refusal of unknown steps.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "gemm/gemm_tune_steps.hpp"
#include "gemm/gemm_tuning.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

gemm::GemmProblem problem(size_t m, size_t n, size_t k, bool transpose_a, bool transpose_b) {
  gemm::GemmProblem p;
  p.shape.m = m;
  p.shape.n = n;
  p.shape.k = k;
  p.shape.transpose_a = transpose_a;
  p.shape.transpose_b = transpose_b;
  return p;
}

}  // namespace

TEST_CASE("gemm tune steps: the error ratio is 1 at twice the float32 dot-product bound, huge when not finite") {
  // k = 100, Σ|a·b| = 10: the bound is 2·100·5.96e-8·10 = 1.192e-4.
  CHECK(gemm::gemm_error_ratio(3.0, 3.0, 10.0, 100) == 0.0);
  CHECK(gemm::gemm_error_ratio(3.0 + 1.192e-4, 3.0, 10.0, 100) == doctest::Approx(1.0).epsilon(1e-6));
  CHECK(gemm::gemm_error_ratio(3.0 - 0.5 * 1.192e-4, 3.0, 10.0, 100) == doctest::Approx(0.5).epsilon(1e-6));
  CHECK(gemm::gemm_error_ratio(std::numeric_limits<double>::quiet_NaN(), 3.0, 10.0, 100) == 1e30);
  CHECK(gemm::gemm_error_ratio(std::numeric_limits<double>::infinity(), 3.0, 10.0, 100) == 1e30);
}

TEST_CASE("gemm tune steps: CLBlast's defaults, evaluated through the routine, are timed and found correct") {
  auto& ctx = test::test_context();
  const std::vector<gemm::GemmProblem> problems = {
      problem(256, 128, 96, false, false), problem(256, 128, 96, false, true), problem(96, 128, 256, true, false)};
  std::vector<std::string> lines;
  const io::Json result = gemm::run_tune_step(ctx, gemm::evaluate_step({}, problems, 1),
                                             [&](LogLevel, const std::string& line) { lines.push_back(line); });
  gemm::clear_gemm_tuning(ctx);
  REQUIRE(result.at("seconds").size() == 3);
  REQUIRE(result.at("error_ratio").size() == 3);
  for (size_t i = 0; i < 3; ++i) {
    CHECK(result.at("seconds")[i].get<double>() > 0.0);
    CHECK(result.at("error_ratio")[i].get<double>() <= 1.0);
  }
  CHECK(result.at("probe_error_ratio").get<double>() <= 1.0);
  CHECK(result.at("wall_seconds").get<double>() > 0.0);
  // The probe's ratio first, then one line per product.
  REQUIRE(lines.size() == 4);
  CHECK(lines[0].find("correctness probe") != std::string::npos);
  CHECK(lines[1].find("256x128x96 forward: ") == 2);
  CHECK(lines[3].find("96x128x256 backward_weights: ") == 2);
}

TEST_CASE("gemm tune steps: an unknown step or tuner is refused by name") {
  auto& ctx = test::test_context();
  CHECK_THROWS_WITH_AS(gemm::run_tune_step(ctx, gemm::kernel_tuner_step("Nope", 128, 128, 0, 1.0), {}),
                       doctest::Contains("unknown tuner Nope"), Error);
  CHECK_THROWS_WITH_AS(gemm::run_tune_step(ctx, {{"type", "sideways"}}, {}),
                       doctest::Contains("unknown tuning step 'sideways'"), Error);
}
