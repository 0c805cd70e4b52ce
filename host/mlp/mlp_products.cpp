// The matrix products of a network, layer by layer.
#include "mlp/mlp_products.hpp"

namespace mipnerf::mlp {

std::vector<gemm::GemmProblem> mlp_gemm_problems(const MlpConfig& c, size_t rows) {
  c.validate();
  std::vector<gemm::GemmProblem> problems;
  const size_t W = c.width;
  for (size_t i = 0; i < c.depth; ++i) {
    const bool from_features = i == 0;
    const bool skip = i > 0 && skip_after(c, i - 1);
    if (!from_features) {
      gemm::add_gemm_problem(problems, rows, W, W, false, false, 1);  // forward
      gemm::add_gemm_problem(problems, rows, W, W, false, true, 1);   // ∂act_{i−1}
      gemm::add_gemm_problem(problems, W, W, rows, true, false, 1);   // ∂W
    }
    if (from_features || skip) {
      gemm::add_gemm_problem(problems, rows, W, c.input_width, false, false, 1);
      gemm::add_gemm_problem(problems, c.input_width, W, rows, true, false, 1);
    }
  }
  if (c.view_dependence) {
    const size_t Wb = c.bottleneck_width, Wv = c.view_branch_width;
    gemm::add_gemm_problem(problems, rows, Wb, W, false, false, 1);
    gemm::add_gemm_problem(problems, rows, W, Wb, false, true, 1);
    gemm::add_gemm_problem(problems, W, Wb, rows, true, false, 1);
    gemm::add_gemm_problem(problems, rows, Wv, Wb, false, false, 1);
    gemm::add_gemm_problem(problems, rows, Wb, Wv, false, true, 1);
    gemm::add_gemm_problem(problems, Wb, Wv, rows, true, false, 1);
  }
  return problems;
}

}  // namespace mipnerf::mlp
