// The matrix products of a network, layer by layer, and the host MLP's blocks of them.
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

namespace {

HostMlpProduct as_host_product(const gemm::GemmProblem& p) {
  const gemm::HostProductShape shape{p.shape.transpose_a, p.shape.transpose_b, p.shape.m, p.shape.n, p.shape.k};
  return {p, shape, gemm::host_product_label(shape)};
}

}  // namespace

std::vector<HostMlpProduct> host_mlp_products(const MlpConfig& config, size_t samples_per_ray,
                                              const HostMlpOptions& options) {
  const size_t forward_rows = forward_block_rows(options, samples_per_ray);
  const size_t backward_rows = backward_block_rows(options, config.width, samples_per_ray);
  std::vector<HostMlpProduct> products;
  // Blocks of one size: mlp_gemm_problems' list as it is; else its forward products at the forward's rows, then its
  // backward ones at the backward's.
  for (const gemm::GemmProblem& p : mlp_gemm_problems(config, forward_rows)) {
    if (forward_rows == backward_rows || p.kind() == gemm::GemmKind::forward) products.push_back(as_host_product(p));
  }
  if (forward_rows == backward_rows) return products;
  for (const gemm::GemmProblem& p : mlp_gemm_problems(config, backward_rows)) {
    if (p.kind() != gemm::GemmKind::forward) products.push_back(as_host_product(p));
  }
  return products;
}

}  // namespace mipnerf::mlp
