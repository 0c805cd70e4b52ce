// CLBlast row-major SGEMM against the CPU loop, on shapes that are and are not multiples of 16.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "cl/error.hpp"
#include "gemm/clblast_check.hpp"
#include "gemm/gemm.hpp"
#include "ref/gemm_ref.hpp"
#include "support/gemm_backends.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

std::vector<float> random_matrix(size_t count, std::mt19937& rng) {
  std::uniform_real_distribution<float> dist(-1.0f, 1.0f);
  std::vector<float> m(count);
  for (auto& v : m) v = dist(rng);
  return m;
}

// Checks device C against the double reference. Tolerance: each element is a k-term dot product of
// values in [-1, 1]; float32 accumulation error grows like sqrt(k)·eps·sum|a·b| ≤ sqrt(k)·eps·k, and
// 4·k·eps (eps = 2^-24 ≈ 6e-8) bounds it with margin for any summation order CLBlast uses.
void check_gemm_on(gemm::GemmBackend backend, const gemm::GemmShape& s, float alpha, float beta, size_t pad) {
  auto& ctx = test::test_context();
  INFO("backend " << enum_name(backend));
  std::mt19937 rng(static_cast<unsigned>(s.m * 131 + s.n * 17 + s.k));
  const size_t a_rows = s.transpose_a ? s.k : s.m, a_cols = s.transpose_a ? s.m : s.k;
  const size_t b_rows = s.transpose_b ? s.n : s.k, b_cols = s.transpose_b ? s.k : s.n;
  const size_t lda = a_cols + pad, ldb = b_cols + pad, ldc = s.n + pad;
  const size_t offset = pad;  // a non-zero offset exercises MatrixView::offset
  auto a = random_matrix(offset + a_rows * lda, rng);
  auto b = random_matrix(offset + b_rows * ldb, rng);
  auto c = random_matrix(offset + s.m * ldc, rng);
  ocl::DeviceArray<float> a_dev(ctx, a.size(), "A"), b_dev(ctx, b.size(), "B"), c_dev(ctx, c.size(), "C");
  a_dev.upload(ctx, a);
  b_dev.upload(ctx, b);
  c_dev.upload(ctx, c);
  gemm::sgemm(ctx, backend, s, alpha, ocl::view(a_dev, lda, offset), ocl::view(b_dev, ldb, offset), beta,
              ocl::view(c_dev, ldc, offset), "test");
  const auto c_device = c_dev.download(ctx);
  ref::gemm<float>(s, alpha, a.data() + offset, lda, b.data() + offset, ldb, beta, c.data() + offset, ldc);
  const double tolerance = 4.0 * static_cast<double>(s.k) * 6e-8 * (std::abs(alpha) + 1.0) + 1e-6;
  double worst = 0.0;
  for (size_t i = 0; i < s.m; ++i) {
    for (size_t j = 0; j < s.n; ++j) {
      const size_t at = offset + i * ldc + j;
      REQUIRE(std::isfinite(c_device[at]));
      worst = std::max(worst, std::abs(static_cast<double>(c_device[at]) - c[at]));
    }
  }
  INFO("m=" << s.m << " n=" << s.n << " k=" << s.k << " tA=" << s.transpose_a << " tB=" << s.transpose_b);
  CHECK(worst <= tolerance);
  // Padding between rows is never written.
  if (pad > 0) CHECK(c_device[offset + s.n] == c[offset + s.n]);
}

// The same product on every backend the test device runs.
void check_gemm(const gemm::GemmShape& s, float alpha, float beta, size_t pad) {
  for (const gemm::GemmBackend backend : test::supported_gemm_backends(test::test_context())) {
    check_gemm_on(backend, s, alpha, beta, pad);
  }
}

}  // namespace

TEST_CASE("gemm: CLBlast and the host BLAS match the CPU loop on MLP-like and awkward shapes") {
  struct Case {
    size_t m, n, k;
  };
  for (const Case& c : {Case{64, 64, 64}, Case{1, 1, 1}, Case{17, 33, 7}, Case{100, 3, 129}, Case{255, 256, 96},
                        Case{5, 128, 283}}) {
    for (int transposes = 0; transposes < 4; ++transposes) {
      gemm::GemmShape s;
      s.m = c.m;
      s.n = c.n;
      s.k = c.k;
      s.transpose_a = transposes & 1;
      s.transpose_b = transposes & 2;
      check_gemm(s, 1.0f, 0.0f, 0);
    }
  }
}

TEST_CASE("gemm: alpha, beta accumulation, offsets and leading dimensions") {
  gemm::GemmShape s;
  s.m = 37;
  s.n = 19;
  s.k = 23;
  check_gemm(s, 0.5f, 1.0f, 3);  // beta = 1 accumulates into C, as the weight gradients do
  s.transpose_a = true;
  check_gemm(s, -2.0f, 0.25f, 5);
}

TEST_CASE("gemm: undersized buffers are refused before CLBlast runs") {
  auto& ctx = test::test_context();
  ocl::DeviceArray<float> a(ctx, 16 * 16, "A"), b(ctx, 16 * 16, "B"), c(ctx, 16 * 15, "C too small");
  gemm::GemmShape s;
  s.m = s.n = s.k = 16;
  CHECK_THROWS_WITH_AS(gemm::sgemm(ctx, gemm::GemmBackend::clblast, s, 1.0f, ocl::view(a, 16), ocl::view(b, 16), 0.0f, ocl::view(c, 16), "tiny"),
                       doctest::Contains("C too small"), Error);
  CHECK_THROWS_WITH_AS(gemm::sgemm(ctx, gemm::GemmBackend::clblast, s, 1.0f, ocl::view(a, 8), ocl::view(b, 16), 0.0f, ocl::view(a, 16), "tiny"),
                       doctest::Contains("leading dimension"), Error);
  CHECK(gemm::clblast_status_name(clblast::StatusCode::kInsufficientMemoryC) == "kInsufficientMemoryC");
  CHECK(gemm::clblast_status_name(clblast::StatusCode::kOpenCLOutOfResources) == "CL_OUT_OF_RESOURCES");
}
