// Small element-wise utilities shared by stages: scaled copy and accumulation of float arrays.

// y[i] = SCALE_FACTOR * x[i]. SCALE_FACTOR is a compile-time option (default 1): the program builder's
// smallest specialisation, also used by the tests of the build system.
#ifndef SCALE_FACTOR
#define SCALE_FACTOR 1.0f
#endif
__kernel void scale_f32(__global const float* x, __global float* y, const uint n) {
  const size_t i = get_global_id(0);
  if (i >= n) return;
  y[i] = SCALE_FACTOR * x[i];
}

// y[i] += a * x[i]: accumulates gradients from several passes into one set.
__kernel void axpy_f32(const float a, __global const float* x, __global float* y, const uint n) {
  const size_t i = get_global_id(0);
  if (i >= n) return;
  y[i] += a * x[i];
}
