// The matrix products of a network: what `mipnerf-cl tune` tunes for, the GEMM benchmarks time, and (at the host MLP's
// block rows) the shapes whose CPU GEMM library tune chooses.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "gemm/cpu_sgemm.hpp"
#include "gemm/gemm_tuning.hpp"
#include "mlp/host_mlp.hpp"
#include "mlp/mlp_config.hpp"

namespace mipnerf::mlp {

// The distinct products whose cost matters for `config` at `rows` rows (trunk, skip, bottleneck and view
// branch; the thin heads are left out), with how often each occurs in one forward + backward.
std::vector<gemm::GemmProblem> mlp_gemm_problems(const MlpConfig& config, size_t rows);

// One product as the host MLP runs it on one block: its shape (the tuning file's key is its label) and the problem it
// is (count, FLOPs, kind).
struct HostMlpProduct {
  gemm::GemmProblem problem;
  gemm::HostProductShape shape;
  std::string label;  // gemm::host_product_label(shape), e.g. "forward 256x256x256"
};

// The products the host MLP runs for `config` at `samples_per_ray` with `options`' blocks: the forward's at its forward
// block rows, the backward's (data and weights) at its backward block rows (mlp::forward_block_rows,
// backward_block_rows), in mlp_gemm_problems' order. The one place these shapes are computed: tune's host step and
// bench_gemm_libs time them, the host MLP runs them.
std::vector<HostMlpProduct> host_mlp_products(const MlpConfig& config, size_t samples_per_ray,
                                              const HostMlpOptions& options = {});

}  // namespace mipnerf::mlp
