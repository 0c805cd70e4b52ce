// Adam over the MLP's flat parameter buffer, the learning-rate schedule of supplement eq. 24, global
// gradient-norm clipping, and the optimiser state a checkpoint saves.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "cl/buffer.hpp"
#include "cl/context.hpp"

namespace mipnerf::ops {
class AdamKernels;
}

namespace mipnerf::mlp {

// Supplement eq. 24 (official learning_rate_decay): lr(step) = delay(step) · exp((1 − t)·ln lr_init +
// t·ln lr_final), t = clamp(step / max_steps, 0, 1), delay = warmup_mult + (1 − warmup_mult) ·
// sin(π/2 · clamp(step / warmup_steps, 0, 1)) (1 when warmup_steps = 0).
struct LrSchedule {
  double lr_init = 5e-4;        // learning rate at step 0 (before the warm-up factor)
  double lr_final = 5e-6;       // learning rate at max_steps
  int64_t max_steps = 1000000;  // steps of the run: the log-linear decay spans them
  int64_t warmup_steps = 2500;  // n_w: length of the sine warm-up; 0 disables it
  double warmup_mult = 0.01;    // λ_w: the warm-up factor at step 0

  // Throws mipnerf::Error unless the rates are positive and finite, the step counts ≥ 0 (max_steps > 0)
  // and warmup_mult is in [0, 1].
  void validate() const;
};

// The learning rate for `step`, as the official train loop calls it with the 1-based number of the update.
double learning_rate(const LrSchedule& schedule, int64_t step);

struct AdamHyper {
  // The decays as the official code gives them (flax Adam's Python floats); the kernel gets β and 1 − β each rounded
  // to float from these, and the bias corrections are computed from them in double.
  double beta1 = 0.9;          // first-moment decay β1
  double beta2 = 0.999;        // second-moment decay β2
  float epsilon = 1e-8f;       // ε added to √v̂
  double grad_max_norm = 0.0;  // clip the global gradient norm to this (official: mult = min(1, max / (1e-7 + norm))); 0 = off
};

// What the device reduction found in a gradient buffer.
struct GradientStats {
  double norm = 0.0;      // √Σ g² over the finite elements (accumulated in float per slice, in double across)
  size_t non_finite = 0;  // NaN or ±Inf elements
  // False when any element is non-finite or the norm overflowed: the trainer skips such a step.
  bool finite() const;
};

// The optimiser state, as a checkpoint stores it: restoring it continues the run exactly.
struct AdamState {
  int64_t step = 0;      // updates applied so far (the next update uses t = step + 1 for bias correction)
  std::vector<float> m;  // first moments, the parameter buffer's layout
  std::vector<float> v;  // second moments
};

class Adam {
 public:
  // Moments start at zero, step at 0.
  Adam(ocl::Context& ctx, size_t n_params, const AdamHyper& hyper = {});
  // Bytes an optimiser of `n_params` parameters takes on the device: the two moments and the reduction's partials.
  static size_t bytes_for(size_t n_params);
  ~Adam();
  Adam(const Adam&) = delete;
  Adam& operator=(const Adam&) = delete;

  const AdamHyper& hyper() const { return hyper_; }
  size_t size() const { return n_params_; }
  int64_t step_count() const { return step_; }

  // Norm and non-finite count of grads[0 … size()), by a device reduction; blocks to read ~1k partial sums.
  GradientStats gradient_stats(const ocl::DeviceArray<float>& grads);

  // One update (asynchronous): params −= lr · m̂ / (√v̂ + ε). `stats` must come from gradient_stats() of
  // these grads; it supplies the clipping scale. Throws (and changes nothing) when stats are not finite —
  // skip the step instead — or when grad_max_norm > 0 and no stats are given.
  void step(ocl::DeviceArray<float>& params, const ocl::DeviceArray<float>& grads, double lr,
            const GradientStats* stats);

  // The state (blocking download) and its exact restoration (sizes are checked).
  AdamState state() const;
  void restore(const AdamState& state);

 private:
  ocl::Context* ctx_;
  size_t n_params_;
  AdamHyper hyper_;
  int64_t step_ = 0;
  ocl::DeviceArray<float> m_, v_;
  size_t n_partials_;
  ocl::DeviceArray<float> sumsq_partials_;
  ocl::DeviceArray<cl_uint> non_finite_partials_;
  std::unique_ptr<ops::AdamKernels> kernels_;
};

}  // namespace mipnerf::mlp
