// CPU reference of kernels/adam.cl in double precision (same names and argument order as the kernels).
#pragma once

#include <cstddef>
#include <cstdint>

namespace mipnerf::ref {

// Mirror of grad_norm_partial: slice p sums g² over its finite elements p, p + n_partials, …, and counts
// its NaN/Inf elements.
void grad_norm_partial(const double* grad, size_t n, double* sumsq, uint32_t* non_finite, size_t n_partials);

// Mirror of adam_step: g = grad·grad_scale; m = β1·m + (1−β1)·g; v = β2·v + (1−β2)·g², with 1 − β given as
// one_minus_beta1/2 (as the kernel takes them); params −= lr · (m·inv_bias1) / (√v·√inv_bias2 + ε), for elements
// 0 … n − 1 (√v̂ split as the kernel splits it).
void adam_step(double* params, const double* grad, double* m, double* v, size_t n, double lr, double beta1,
               double beta2, double one_minus_beta1, double one_minus_beta2, double epsilon, double inv_bias1,
               double inv_bias2, double grad_scale);

}  // namespace mipnerf::ref
