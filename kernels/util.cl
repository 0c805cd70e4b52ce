// Small utilities: a scaled copy of a float array (the build system's tests), and the RNG exposed for tests.

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

// out[4i..4i+3] = rng_uniform4(seed, i, step, slot, stream): exposes the RNG for tests and benchmarks.
__kernel void rng_uniform4_fill(const ulong seed, const uint step, const uint slot, const uint stream,
                                __global float* out, const uint n_items) {
  const uint i = get_global_id(0);
  if (i >= n_items) return;
  const float4 u = rng_uniform4(seed, i, step, slot, stream);
  vstore4(u, i, out);
}

// out[4i..4i+3] = rng_normal4(seed, i, step, slot, stream): the normal draws (density noise), for tests.
__kernel void rng_normal4_fill(const ulong seed, const uint step, const uint slot, const uint stream,
                               __global float* out, const uint n_items) {
  const uint i = get_global_id(0);
  if (i >= n_items) return;
  vstore4(rng_normal4(seed, i, step, slot, stream), i, out);
}

// Raw Philox words for the known-answer test: out[4i..] = philox4x32_10(counters[i], key).
__kernel void philox_words(__global const uint* counters, const uint key0, const uint key1, __global uint* out,
                           const uint n_items) {
  const uint i = get_global_id(0);
  if (i >= n_items) return;
  vstore4(philox4x32_10(vload4(i, counters), (uint2)(key0, key1)), i, out);
}
