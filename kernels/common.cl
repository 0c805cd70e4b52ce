// Shared helpers for every mipnerf-cl program; prepended before a stage's own file.
// Plain OpenCL C 1.2. Conventions used by all kernels:
//  - 1-D launches are padded to a multiple of the work-group size (host/cl/launch.hpp), so every
//    kernel starts with `if (i >= n) return;` and none uses a barrier after that guard.
//  - Arrays are flat, row-major, float32; a 3-vector is 3 consecutive floats (never float3, whose
//    16-byte alignment would change the layout).

#ifndef MIPNERF_COMMON_CL
#define MIPNERF_COMMON_CL

// Loads/stores a packed 3-vector at element index i (i.e. floats 3i..3i+2).
#ifndef MIPNERF_TEST_FAULT
inline float3 load3(__global const float* p, size_t i) { return (float3)(p[3 * i], p[3 * i + 1], p[3 * i + 2]); }
#else
// Test-only, never defined otherwise: `mipnerf-selftest --inject-build-option=-DMIPNERF_TEST_FAULT` stands in for a
// driver with a broken vector load. Every 3-vector read loses the low 8 bits of its mantissas (relative error up to
// 2^-16, far beyond every stage's float32 bound), and the self-test must fail on it.
inline float drop_low_bits(float x) { return as_float(as_uint(x) & 0xFFFFFF00u); }
inline float3 load3(__global const float* p, size_t i) {
  return (float3)(drop_low_bits(p[3 * i]), drop_low_bits(p[3 * i + 1]), drop_low_bits(p[3 * i + 2]));
}
#endif
inline void store3(__global float* p, size_t i, float3 v) {
  p[3 * i] = v.x;
  p[3 * i + 1] = v.y;
  p[3 * i + 2] = v.z;
}

// Packed camera layout, [C][CAMERA_STRIDE] floats; mirrors host/data/camera.hpp (camera_layout).
#define CAMERA_TO_WORLD 0 /* 12 floats, 3x4 row-major, OpenGL axes (camera looks down -z) */
#define CAMERA_FOCAL_X 12 /* pixels */
#define CAMERA_FOCAL_Y 13
#define CAMERA_CENTER_X 14 /* principal point, pixels from the left edge */
#define CAMERA_CENTER_Y 15 /* pixels from the top edge */
#define CAMERA_WIDTH 16
#define CAMERA_HEIGHT 17
#define CAMERA_NEAR 18
#define CAMERA_FAR 19
#define CAMERA_LOSSMULT 20
#define CAMERA_LENS_TABLE 21 /* bits of a uint: the lens table offset + 1 in float4 elements; 0 = pinhole */
#define CAMERA_STRIDE 24

// ---- Counter-based RNG: Philox4x32-10 (Salmon et al., SC'11) ----
// Random numbers are a pure function of (seed, counter), so jittered sampling is reproducible across
// runs, devices and chunkings. Counter = (item, step, slot, stream): `item` is the ray (or pixel),
// `slot` a sample index within it, `stream` one of the RNG_STREAM_* purposes below, so the uses never
// share numbers. host/core/rng.hpp mirrors the uniforms bit for bit.
#define RNG_STREAM_STRATIFIED 0u  /* jitter of stratified interval edges */
#define RNG_STREAM_RESAMPLE 1u    /* jitter of inverse-CDF resampling */
#define RNG_STREAM_BATCH 2u       /* choice of training pixels */
#define RNG_STREAM_SUBPIXEL 3u    /* sub-pixel position of a ray (supersampling) */
#define RNG_STREAM_DENSITY_NOISE 4u /* noise added to the raw density while training (render.cl) */

inline uint4 philox4x32_10(uint4 counter, uint2 key) {
  for (int round = 0; round < 10; ++round) {
    const uint hi0 = mul_hi(0xD2511F53u, counter.x), lo0 = 0xD2511F53u * counter.x;
    const uint hi1 = mul_hi(0xCD9E8D57u, counter.z), lo1 = 0xCD9E8D57u * counter.z;
    counter = (uint4)(hi1 ^ counter.y ^ key.x, lo1, hi0 ^ counter.w ^ key.y, lo0);
    key += (uint2)(0x9E3779B9u, 0xBB67AE85u);
  }
  return counter;
}

// Four uniform floats in [0, 1): the top 24 bits of each word, so every value is exact in float32
// and 1.0 is never returned.
inline float4 rng_uniform4(ulong seed, uint item, uint step, uint slot, uint stream) {
  const uint4 bits = philox4x32_10((uint4)(item, step, slot, stream), (uint2)((uint)seed, (uint)(seed >> 32)));
  return convert_float4(bits >> 8) * (1.0f / 16777216.0f);
}

// Four standard normal draws from the four uniforms of rng_uniform4 (same counter), by the Box–Muller transform:
// (u0, u1) → r0·cos(2π·u1), r0·sin(2π·u1) with r0 = sqrt(−2·log(1 − u0)), and (u2, u3) likewise. Guard: 1 − u is
// in [2^-24, 1] and exact in float32 (u < 1 has 24 bits), so the log is finite and every draw is within
// sqrt(48·ln 2) ≈ 5.77 of 0; cospi/sinpi of the exact 2u keep the angle free of a rounded π. host/core/rng.hpp
// (rng_normal4) is the same formula in double: the two agree to a few float32 ulps of each draw, not bit for bit.
inline float4 rng_normal4(ulong seed, uint item, uint step, uint slot, uint stream) {
  const float4 u = rng_uniform4(seed, item, step, slot, stream);
  const float r0 = sqrt(-2.0f * log(1.0f - u.x)), r1 = sqrt(-2.0f * log(1.0f - u.z));
  return (float4)(r0 * cospi(2.0f * u.y), r0 * sinpi(2.0f * u.y), r1 * cospi(2.0f * u.w), r1 * sinpi(2.0f * u.w));
}

#endif
