// The matrix products of a network: what `mipnerf-cl tune` tunes for and the GEMM benchmark times.
#pragma once

#include <cstddef>
#include <vector>

#include "gemm/gemm_tuning.hpp"
#include "mlp/mlp_config.hpp"

namespace mipnerf::mlp {

// The distinct products whose cost matters for `config` at `rows` rows (trunk, skip, bottleneck and view
// branch; the thin heads are left out), with how often each occurs in one forward + backward.
std::vector<gemm::GemmProblem> mlp_gemm_problems(const MlpConfig& config, size_t rows);

}  // namespace mipnerf::mlp
