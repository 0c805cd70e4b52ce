// The MLP on the host CPU, for devices whose buffers live in host memory (gemm_backend=host): forward and backward
// fused row block by row block, with the BLAS (OpenBLAS, one thread per call) for the products and the element-wise
// work done while the block is still in cache.
//
// Why: on a CPU device the products already run on the host BLAS (host_gemm.hpp), and what was left around them were
// whole passes over memory per layer: bias + ReLU after each product, the ReLU mask and the bias sums before each
// backward product, one device kernel each, plus a queue drain per product. Here a block of rows (whole rays, about
// target_block_rows samples) goes through every layer before the next block starts:
//   forward:  act_i = ReLU(in_i · W_i + b_i) — the product into the block's rows, then bias + ReLU on them in cache;
//             each activation is written once (training keeps it for the backward; inference keeps nothing but
//             the outputs and uses per-thread scratch);
//   backward: dz_i = (dact_i masked by act_i > 0) in per-thread scratch; bias sums and weight gradients
//             (in_iᵀ · dz_i) accumulate in a per-thread gradient buffer; dact_{i−1} = dz_i · W_iᵀ goes to the next
//             scratch. No gradient of an activation ever goes to device memory; only ∂loss/∂features, when the
//             caller asks for it, goes to the caller's buffer (each block writes its own rows: no reduction).
// Threads take contiguous ranges of blocks (static, so a given thread count always gives the same result); their
// gradient buffers are added to the network's in thread order at the end. The block decomposition depends on the
// rows only, so training and inference forwards give bit-equal outputs.
//
// The same mathematics as the device path (mlp.hpp) and the reference (ref/mlp): products in float32 with the BLAS's
// summation order, ReLU that keeps NaN.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "gemm/cpu_sgemm.hpp"
#include "mlp/mlp_config.hpp"

namespace mipnerf::mlp {

struct HostMlpOptions {
  size_t target_block_rows = 256;  // rows per block ≈ this, rounded to whole rays (at least one ray)
  // Rows per backward block, ≈ (whole rays); 0: backward_block_rows_for(width). The forward keeps target_block_rows,
  // so training and inference forwards stay bit-equal; the backward's blocks change only its summation order.
  size_t backward_target_block_rows = 0;
  size_t threads = 1;              // worker threads (the device's compute units)
  // Which CPU GEMM library runs which product (default: OpenBLAS for all; tune's per-shape choice when the device's
  // tuning file has one). Each call holds every library to its worker thread: our threads split the rows.
  gemm::HostProductLibraries libraries;
};

// Host addresses of one forward's buffers (mapped device buffers). Row-major, leading dimensions given.
struct HostForwardBuffers {
  const float* params = nullptr;
  const float* features = nullptr;  // [rows][input_width], ld features_ld
  size_t features_ld = 0;
  const float* view_encoding = nullptr;  // [n_rays][view_width], ld view_ld (view dependence only)
  size_t view_ld = 0;
  float* density = nullptr;  // [rows][density_outputs], ld density_ld
  size_t density_ld = 0;
  float* rgb = nullptr;  // [rows][rgb_outputs], ld rgb_ld; null (inference only): density only, no colour head
  size_t rgb_ld = 0;
  std::vector<float*> trunk;  // training: depth × [rows][width] (ld width) kept for the backward; empty: inference
  float* bottleneck = nullptr;   // training with view dependence: [rows][bottleneck_width]
  float* view_hidden = nullptr;  // training with view dependence: [rows][view_branch_width]
  size_t n_rays = 0, samples_per_ray = 0;
};

struct HostBackwardBuffers {
  HostForwardBuffers saved;  // what the forward read and kept (its outputs are not read)
  const float* d_density = nullptr;  // [rows][density_outputs], ld d_density_ld
  size_t d_density_ld = 0;
  const float* d_rgb = nullptr;  // [rows][rgb_outputs], ld d_rgb_ld
  size_t d_rgb_ld = 0;
  float* grads = nullptr;  // [parameters], accumulated into (+=)
  // [rows][input_width], ld d_features_ld: ∂loss/∂features, overwritten (each block its own rows); null: not asked
  // for, and no product for it runs
  float* d_features = nullptr;
  size_t d_features_ld = 0;
};

// Where a call's time went, summed over its threads (seconds of thread time), for the stage profiler.
struct HostMlpTimes {
  double gemm_forward = 0.0, gemm_backward_data = 0.0, gemm_backward_weights = 0.0, elementwise = 0.0;
  double flops_forward = 0.0, flops_backward_data = 0.0, flops_backward_weights = 0.0;
  double total() const { return gemm_forward + gemm_backward_data + gemm_backward_weights + elementwise; }
};

// Whole rays per block of about `target_rows` rows (at least one ray): how the host MLP cuts its passes.
size_t rays_per_block(size_t target_rows, size_t samples_per_ray);

// The backward's default rows per block for a network `width` wide: 2 × target_block_rows from 256 wide up, else
// target_block_rows. Why: each block's weight-gradient products read and write the thread's whole gradient buffer
// (2.4 MB for the paper's network, several times the core's L2; 0.38 MB for the quick preset's), so longer blocks
// halve that traffic per FLOP where it spills. Measured with `mipnerf-cl bench` (PoCL CPU device, 2 EPYC cores,
// 2026-11-26, 4 alternating rounds): paper step 7.0–7.4 s with 512-row backward blocks against 7.9–8.2 s with 256
// (1,024: 7.4–7.8); the quick preset's step was slower with 512 (0.19–0.24 against 0.17–0.21 s, 3 rounds).
size_t backward_block_rows_for(size_t width, size_t target_block_rows);

// The rows of the host MLP's forward and backward blocks for `config` at `samples_per_ray` under `options`: whole
// rays, about target_block_rows (forward) or backward_target_block_rows, else backward_block_rows_for (backward).
// HostMlp cuts its passes by these, and the shapes of its products (mlp_products.hpp) follow from them.
size_t forward_block_rows(const HostMlpOptions& options, size_t samples_per_ray);
size_t backward_block_rows(const HostMlpOptions& options, size_t width, size_t samples_per_ray);

class HostMlp {
 public:
  HostMlp(const MlpConfig& config, HostMlpOptions options);
  ~HostMlp();
  HostMlp(const HostMlp&) = delete;
  HostMlp& operator=(const HostMlp&) = delete;

  const HostMlpOptions& options() const { return options_; }
  size_t rays_per_block(size_t samples_per_ray) const;           // forward blocks
  size_t backward_rays_per_block(size_t samples_per_ray) const;  // backward blocks

  // Thread times are measured only when `timed` (a clock read around each product).
  HostMlpTimes forward(const HostForwardBuffers& b, bool timed);
  HostMlpTimes backward(const HostBackwardBuffers& b, bool timed);

 private:
  struct Worker;
  HostMlpTimes summed_times(size_t threads) const;
  MlpConfig config_;
  ParameterLayout layout_;
  HostMlpOptions options_;
  std::unique_ptr<gemm::HostProductTable> products_;
  std::vector<Worker> workers_;
};

}  // namespace mipnerf::mlp
