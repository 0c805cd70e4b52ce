// CPU reference of kernels/adam.cl.
#include "ref/adam.hpp"

#include <cmath>

namespace mipnerf::ref {

void grad_norm_partial(const double* grad, size_t n, double* sumsq, uint32_t* non_finite, size_t n_partials) {
  for (size_t p = 0; p < n_partials; ++p) {
    double sum = 0.0;
    uint32_t bad = 0;
    for (size_t i = p; i < n; i += n_partials) {
      if (std::isfinite(grad[i])) {
        sum += grad[i] * grad[i];
      } else {
        ++bad;
      }
    }
    sumsq[p] = sum;
    non_finite[p] = bad;
  }
}

void adam_step(double* params, const double* grad, double* m, double* v, size_t n, double lr, double beta1,
               double beta2, double one_minus_beta1, double one_minus_beta2, double epsilon, double inv_bias1,
               double inv_bias2, double grad_scale) {
  for (size_t i = 0; i < n; ++i) {
    const double g = grad[i] * grad_scale;
    m[i] = beta1 * m[i] + one_minus_beta1 * g;
    // The kernel's guards, in the same order (kernels/adam.cl): ((1 − β2)·g)·g, and √v̂ = √v·√inv_bias2, which
    // keep v and √v̂ finite in float32 where the official lax.square(g) and √(v/(1 − β2^t)) overflow to ∞.
    v[i] = beta2 * v[i] + one_minus_beta2 * g * g;
    params[i] -= lr * (m[i] * inv_bias1) / (std::sqrt(v[i]) * std::sqrt(inv_bias2) + epsilon);
  }
}

}  // namespace mipnerf::ref
