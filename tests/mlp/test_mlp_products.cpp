// The products of a network and the shapes the host MLP runs them at (mlp/mlp_products.hpp): the one list that tune's
// host step, bench_gemm_libs and the tests time.
#include <doctest/doctest.h>

#include <set>
#include <string>

#include "mlp/mlp_products.hpp"

using namespace mipnerf;

TEST_CASE("mlp products: host shapes: the forward products at the forward blocks, the others at the backward ones") {
  const mlp::MlpConfig paper;  // 256 wide: the backward's blocks are twice the forward's (backward_block_rows_for)
  const size_t samples = 64;
  const mlp::HostMlpOptions options;
  const size_t forward_rows = mlp::forward_block_rows(options, samples);
  const size_t backward_rows = mlp::backward_block_rows(options, paper.width, samples);
  CHECK(forward_rows == 256);
  CHECK(backward_rows == 512);
  const auto products = mlp::host_mlp_products(paper, samples, options);
  std::set<std::string> labels;
  size_t forward = 0, backward = 0;
  for (const mlp::HostMlpProduct& p : products) {
    INFO(p.label);
    CHECK(labels.insert(p.label).second);  // each shape once
    CHECK(p.label == gemm::host_product_label(p.shape));
    CHECK(p.shape.m == p.problem.shape.m);
    CHECK(p.shape.n == p.problem.shape.n);
    CHECK(p.shape.k == p.problem.shape.k);
    const bool is_forward = p.problem.kind() == gemm::GemmKind::forward;
    (is_forward ? forward : backward) += 1;
    // The rows are m, or k for the weight gradients (aᵀ·b).
    CHECK((p.shape.trans_a ? p.shape.k : p.shape.m) == (is_forward ? forward_rows : backward_rows));
  }
  // Forward: the trunk's W×W (the bottleneck, as wide, has its shape), the features' (first layer and skip: one
  // shape), the view branch. Backward: ∂act and ∂W of the trunk (and bottleneck) and of the view branch, and ∂W of
  // the features (no gradient flows to the features).
  CHECK(forward == 3);
  CHECK(backward == 5);

  // With blocks of one size the list is mlp_gemm_problems' own, in its order (what bench_gemm_libs times).
  mlp::HostMlpOptions one_size;
  one_size.backward_target_block_rows = one_size.target_block_rows;
  const auto same = mlp::host_mlp_products(paper, samples, one_size);
  const auto problems = mlp::mlp_gemm_problems(paper, forward_rows);
  REQUIRE(same.size() == problems.size());
  for (size_t i = 0; i < same.size(); ++i) CHECK(same[i].problem.label == problems[i].label);
}
