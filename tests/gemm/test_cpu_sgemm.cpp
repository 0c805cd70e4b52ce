// The CPU GEMM libraries the host MLP can run its products on (gemm/cpu_sgemm.hpp): each one built in against the
// CPU loop on the host MLP's shapes and on awkward ones, and the per-product choice among them.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "core/error.hpp"
#include "gemm/cpu_sgemm.hpp"
#include "mlp/mlp_config.hpp"
#include "mlp/mlp_products.hpp"
#include "ref/gemm_ref.hpp"
#include "support/scoped_environment.hpp"
#include "support/skip.hpp"

using namespace mipnerf;

namespace {

// One product through `library` against the double loop: padded rows (every ld one more than needed), beta as the
// host MLP uses it (1 for weight gradients, which accumulate; 0 otherwise) over a C that is not zero. Each element
// is a k-term dot product of values in [−1, 1] (plus C): float32 errs by at most (k + 1)·u·(k + 1).
void check_product(const gemm::CpuSgemmLibrary& library, const gemm::HostProductShape& s) {
  INFO(library.name << " " << gemm::host_product_label(s));
  std::mt19937 rng(static_cast<unsigned>(s.m * 7 + s.n * 3 + s.k));
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const size_t lda = (s.trans_a ? s.m : s.k) + 1, ldb = (s.trans_b ? s.k : s.n) + 1, ldc = s.n + 1;
  std::vector<float> a((s.trans_a ? s.k : s.m) * lda), b((s.trans_b ? s.n : s.k) * ldb), c(s.m * ldc);
  for (auto* v : {&a, &b, &c}) {
    for (float& x : *v) x = u(rng);
  }
  const float beta = s.trans_a ? 1.0f : 0.0f;
  std::vector<double> want(c.begin(), c.end());
  const std::vector<double> ad(a.begin(), a.end()), bd(b.begin(), b.end());
  const gemm::GemmShape shape{s.trans_a, s.trans_b, s.m, s.n, s.k};
  ref::gemm<double>(shape, 1.0, ad.data(), lda, bd.data(), ldb, beta, want.data(), ldc);
  library.sgemm(s.trans_a, s.trans_b, int(s.m), int(s.n), int(s.k), a.data(), int(lda), b.data(), int(ldb), beta,
                c.data(), int(ldc));
  const double bound = static_cast<double>((s.k + 1) * (s.k + 1)) * std::ldexp(1.0, -24);
  double worst = 0;
  for (size_t i = 0; i < s.m; ++i) {
    for (size_t j = 0; j < s.n; ++j) {
      REQUIRE(std::isfinite(c[i * ldc + j]));
      worst = std::max(worst, std::abs(c[i * ldc + j] - want[i * ldc + j]));
    }
    CHECK(c[i * ldc + s.n] == static_cast<float>(want[i * ldc + s.n]));  // the padding is never written
  }
  CHECK(worst <= bound);
}

std::vector<gemm::HostProductShape> shapes_to_check() {
  mlp::MlpConfig quick;  // the quick preset's network at the host MLP's 256-row blocks
  quick.width = 128, quick.input_width = 72, quick.view_branch_width = 64, quick.bottleneck_width = 128;
  quick.depth = 4, quick.skip_layer = 2;
  std::vector<gemm::HostProductShape> shapes;
  for (const auto& p : mlp::host_mlp_products(quick, 64)) shapes.push_back(p.shape);  // 256-row blocks both ways
  for (const bool ta : {false, true}) {  // awkward sizes: nothing a multiple of a vector width
    for (const bool tb : {false, true}) {
      if (!(ta && tb)) shapes.push_back({ta, tb, 37, 29, 53});
    }
  }
  return shapes;
}

}  // namespace

TEST_CASE("cpu gemm libraries: each one built in matches the CPU loop on the host MLP's shapes and awkward ones") {
  const auto& libraries = gemm::cpu_sgemm_libraries();
  if (libraries.empty()) {
    test::skip_test("no CPU GEMM library is built in (Debian package libopenblas-dev)");
    return;
  }
  CHECK(libraries.front().name == "openblas");
  for (const auto& library : libraries) {
    CHECK_FALSE(library.version.empty());
    for (const auto& shape : shapes_to_check()) {
      if (!library.every_shape && shape.trans_b) {
        // libxsmm 1.17 has no JIT kernel for these: it must say so, never compute something else.
        CHECK_THROWS_WITH_AS(check_product(library, shape), doctest::Contains("no JIT kernel"), Error);
        continue;
      }
      check_product(library, shape);
    }
  }
}

TEST_CASE("cpu gemm libraries: the per-product choice resolves labels, falls back, and refuses what it cannot run") {
  const auto& libraries = gemm::cpu_sgemm_libraries();
  if (libraries.empty()) {
    test::skip_test("no CPU GEMM library is built in (Debian package libopenblas-dev)");
    return;
  }
  const gemm::CpuSgemmLibrary& other = libraries.back();  // the last built in (OpenBLAS when it is the only one)
  gemm::HostProductLibraries choice;
  choice.by_product["forward 256x128x128"] = other.name;
  const gemm::HostProductTable table(choice);
  CHECK(&table.library_for({false, false, 256, 128, 128}) == &gemm::cpu_sgemm_library(other.name));
  CHECK(table.library_for({false, false, 256, 128, 64}).name == "openblas");  // no choice: the fallback
  CHECK(table.library_for({false, true, 256, 128, 128}).name == "openblas");  // same sizes, another kind
  CHECK(gemm::host_product_label({true, false, 72, 128, 256}) == "backward_weights 72x128x256");

  choice.by_product = {{"sideways 1x2x3", "openblas"}};
  CHECK_THROWS_WITH_AS(gemm::HostProductTable{choice}, doctest::Contains("sideways"), Error);
  choice.by_product = {{"forward 1x2", "openblas"}};
  CHECK_THROWS_WITH_AS(gemm::HostProductTable{choice}, doctest::Contains("forward 1x2"), Error);
  choice.by_product = {{"forward 1x2x3", "nosuchlib"}};
  CHECK_THROWS_WITH_AS(gemm::HostProductTable{choice}, doctest::Contains("'nosuchlib' is not built in"), Error);

  // MIPNERF_HOST_GEMM_LIBRARY overrides every choice, and only names a library that runs every product.
  gemm::HostProductLibraries openblas_chosen;
  openblas_chosen.by_product["forward 256x128x64"] = "openblas";
  for (const auto& library : libraries) {
    test::ScopedEnvironment forced("MIPNERF_HOST_GEMM_LIBRARY", library.name);
    if (library.every_shape) {
      CHECK(gemm::HostProductTable(openblas_chosen).library_for({false, false, 256, 128, 64}).name == library.name);
    } else {
      CHECK_THROWS_WITH_AS(gemm::HostProductTable{openblas_chosen}, doctest::Contains("cannot run every product"),
                           Error);
    }
  }
}

// The test command installs every CPU GEMM library the host MLP can use (scripts/install-deps.sh); CMake leaves out the
// ones it does not find, which would make the tests above check fewer libraries without a word. Each one missing is
// a skip (naming its package), which the test command fails on.
TEST_CASE("cpu gemm libraries: every library the test command installs is built in") {
  const std::vector<std::string> left_out = gemm::cpu_sgemm_libraries_left_out();
  for (const char* name : {"openblas", "blis", "onednn", "libxsmm"}) {
    CAPTURE(name);
    const bool built_in = gemm::cpu_sgemm_libraries().end() !=
                          std::find_if(gemm::cpu_sgemm_libraries().begin(), gemm::cpu_sgemm_libraries().end(),
                                       [&](const gemm::CpuSgemmLibrary& library) { return library.name == name; });
    const bool said_left_out = std::any_of(left_out.begin(), left_out.end(), [&](const std::string& line) {
      return line.rfind(std::string(name) + ":", 0) == 0;
    });
    CHECK(built_in != said_left_out);  // each library is one or the other, never neither
    if (said_left_out) test::skip_test("the CPU GEMM library " + std::string(name) + " is not built in: install it "
                                       "and configure again");
  }
}
