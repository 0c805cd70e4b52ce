// Adam, the learning-rate schedule and gradient statistics.
#include "mlp/adam.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.hpp"
#include "ops/adam.hpp"

namespace mipnerf::mlp {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Slices of the norm reduction: enough work-items to fill a GPU, few enough to read back cheaply.
constexpr size_t kNormPartials = 1024;

}  // namespace

void LrSchedule::validate() const {
  if (!(lr_init > 0.0) || !(lr_final > 0.0) || !std::isfinite(lr_init) || !std::isfinite(lr_final)) {
    throw Error("learning-rate schedule: lr_init and lr_final must be positive and finite (got " +
                std::to_string(lr_init) + ", " + std::to_string(lr_final) + ")");
  }
  if (max_steps <= 0) throw Error("learning-rate schedule: max_steps must be positive");
  if (warmup_steps < 0) throw Error("learning-rate schedule: warmup_steps must not be negative");
  if (!(warmup_mult >= 0.0 && warmup_mult <= 1.0)) {
    throw Error("learning-rate schedule: warmup_mult must be in [0, 1] (got " + std::to_string(warmup_mult) + ")");
  }
}

double learning_rate(const LrSchedule& s, int64_t step) {
  s.validate();
  double delay = 1.0;
  if (s.warmup_steps > 0) {
    const double ramp = std::clamp(static_cast<double>(step) / static_cast<double>(s.warmup_steps), 0.0, 1.0);
    delay = s.warmup_mult + (1.0 - s.warmup_mult) * std::sin(0.5 * kPi * ramp);
  }
  const double t = std::clamp(static_cast<double>(step) / static_cast<double>(s.max_steps), 0.0, 1.0);
  return delay * std::exp(std::log(s.lr_init) * (1.0 - t) + std::log(s.lr_final) * t);
}

bool GradientStats::finite() const { return non_finite == 0 && std::isfinite(norm); }

size_t Adam::bytes_for(size_t n_params) {
  const size_t n_partials = std::max<size_t>(1, std::min(kNormPartials, n_params));
  return 2 * n_params * sizeof(float) + n_partials * (sizeof(float) + sizeof(cl_uint));
}

Adam::Adam(ocl::Context& ctx, size_t n_params, const AdamHyper& hyper)
    : ctx_(&ctx),
      n_params_(n_params),
      hyper_(hyper),
      m_(ctx, n_params, "adam m [params]"),
      v_(ctx, n_params, "adam v [params]"),
      n_partials_(std::max<size_t>(1, std::min(kNormPartials, n_params))),
      sumsq_partials_(ctx, n_partials_, "gradient sum-of-squares partials [slices]"),
      non_finite_partials_(ctx, n_partials_, "gradient non-finite counts [slices]"),
      kernels_(std::make_unique<ops::AdamKernels>(ctx)) {
  if (!(hyper.beta1 >= 0.0 && hyper.beta1 < 1.0) || !(hyper.beta2 >= 0.0 && hyper.beta2 < 1.0)) {
    throw Error("Adam: beta1 and beta2 must be in [0, 1)");
  }
  if (!(hyper.epsilon > 0.0f)) throw Error("Adam: epsilon must be positive");
  if (!(hyper.grad_max_norm >= 0.0)) throw Error("Adam: grad_max_norm must be ≥ 0 (0 disables clipping)");
  m_.fill(ctx, 0.0f);
  v_.fill(ctx, 0.0f);
}

Adam::~Adam() = default;

GradientStats Adam::gradient_stats(const ocl::DeviceArray<float>& grads) {
  kernels_->grad_norm_partial(grads, n_params_, sumsq_partials_, non_finite_partials_, n_partials_);
  const auto sumsq = sumsq_partials_.download(*ctx_);
  const auto non_finite = non_finite_partials_.download(*ctx_);
  GradientStats stats;
  double total = 0.0;
  for (size_t p = 0; p < n_partials_; ++p) {
    total += static_cast<double>(sumsq[p]);
    stats.non_finite += non_finite[p];
  }
  stats.norm = std::sqrt(total);
  return stats;
}

void Adam::step(ocl::DeviceArray<float>& params, const ocl::DeviceArray<float>& grads, double lr,
                const GradientStats* stats) {
  if (stats && !stats->finite()) {
    throw Error("Adam: the gradient has " + std::to_string(stats->non_finite) +
                " non-finite elements (norm " + std::to_string(stats->norm) + "); skip this step");
  }
  if (hyper_.grad_max_norm > 0.0 && !stats) {
    throw Error("Adam: gradient clipping is on (grad_max_norm " + std::to_string(hyper_.grad_max_norm) +
                ") but no gradient statistics were given; call gradient_stats() first");
  }
  if (!(lr >= 0.0) || !std::isfinite(lr)) throw Error("Adam: learning rate " + std::to_string(lr) + " is not valid");
  const int64_t t = step_ + 1;
  ops::AdamStepArgs args;
  args.lr = static_cast<float>(lr);
  args.beta1 = static_cast<float>(hyper_.beta1);
  args.beta2 = static_cast<float>(hyper_.beta2);
  // 1 − β in double, then rounded: float(0.001), not 1.0f − float(0.999) (1.3e-5 off; tests/official adam.json).
  args.one_minus_beta1 = static_cast<float>(1.0 - hyper_.beta1);
  args.one_minus_beta2 = static_cast<float>(1.0 - hyper_.beta2);
  args.epsilon = hyper_.epsilon;
  // Bias corrections in double from the hyperparameters (from float(0.999), 1 − β2^t would be 1.3e-5 off at t = 42).
  args.inv_bias1 = static_cast<float>(1.0 / (1.0 - std::pow(hyper_.beta1, t)));
  args.inv_bias2 = static_cast<float>(1.0 / (1.0 - std::pow(hyper_.beta2, t)));
  if (hyper_.grad_max_norm > 0.0) {
    // The official clip: mult = min(1, max_norm / (1e-7 + norm)); the 1e-7 keeps a zero gradient finite.
    args.grad_scale = static_cast<float>(std::min(1.0, hyper_.grad_max_norm / (1e-7 + stats->norm)));
  }
  kernels_->adam_step(params, grads, m_, v_, n_params_, args);
  step_ = t;
}

AdamState Adam::state() const {
  AdamState state;
  state.step = step_;
  state.m = m_.download(*ctx_);
  state.v = v_.download(*ctx_);
  return state;
}

void Adam::restore(const AdamState& state) {
  if (state.m.size() != n_params_ || state.v.size() != n_params_) {
    throw Error("Adam: the saved state holds " + std::to_string(state.m.size()) + " first and " +
                std::to_string(state.v.size()) + " second moments, but the model has " + std::to_string(n_params_) +
                " parameters (was the checkpoint written for another MLP configuration?)");
  }
  if (state.step < 0) throw Error("Adam: the saved step count is negative");
  m_.upload(*ctx_, state.m);
  v_.upload(*ctx_, state.v);
  step_ = state.step;
}

}  // namespace mipnerf::mlp
