// Shared helpers for every mipnerf-cl program; prepended before a stage's own file.
// Plain OpenCL C 1.2. Conventions used by all kernels:
//  - 1-D launches are padded to a multiple of the work-group size (host/cl/launch.hpp), so every
//    kernel starts with `if (i >= n) return;` and none uses a barrier after that guard; render.cl's
//    SAMPLES_IN_LOCKSTEP kernels, which do use barriers, keep their padding items running instead.
//  - Arrays are flat, row-major, float32; a 3-vector is 3 consecutive floats (never float3, whose
//    16-byte alignment would change the layout).

#ifndef MIPNERF_COMMON_CL
#define MIPNERF_COMMON_CL

// A helper every caller gets inlined: PoCL vectorises a kernel across work-items only when the work-item loop has
// no calls left, and its inliner leaves out functions it finds too costly (stable_softplus: cost 300 > 225).
#define ALWAYS_INLINE inline __attribute__((always_inline))
// A function defined for several value types (float and float16, uint and uint16), each definition written once in a
// macro over the type (below).
#define OVERLOADABLE __attribute__((overloadable))

// Conversions in the definitions written for a scalar and a vector type (W: empty or 16): a C cast for the scalar,
// convert_*16 for the vector. Not the scalar built-in convert_float(uint) and its kind: Intel's CPU compiler does not
// vectorise a kernel across work-items through them (the stratified sampler took 1.9 ms with convert_float(k), 0.45
// with (float)k, on the AVX-512 Xeon).
#define CONVERT_INT(x) ((int)(x))
#define CONVERT_INT16(x) convert_int16(x)
#define CONVERT_UINT(x) ((uint)(x))
#define CONVERT_UINT16(x) convert_uint16(x)
#define CONVERT_ULONG(x) ((ulong)(x))
#define CONVERT_ULONG16(x) convert_ulong16(x)
#define CONVERT_FLOAT(x) ((float)(x))
#define CONVERT_FLOAT16(x) convert_float16(x)

// VECTOR_ITEMS: the program has a stage with explicit vector items (activations, render, gaussian, sample, resample:
// their *_PER_VECTOR / ACTIVATION_ITEMS = 2 switches, which the host sets on PoCL's CPU device). Only then are the
// float16 and uint16 definitions compiled: a program that does not use them does not carry them.
#if SAMPLES_PER_VECTOR || GAUSSIAN_SAMPLES_PER_VECTOR || SAMPLE_GROUPS_PER_VECTOR || RESAMPLE_RAYS_PER_VECTOR || \
    (defined(ACTIVATION_ITEMS) && ACTIVATION_ITEMS == 2 /* ACTIVATION_ITEMS_PER_VECTOR */)
#define VECTOR_ITEMS 1
#else
#define VECTOR_ITEMS 0
#endif

// Loads/stores a packed 3-vector at element index i (i.e. floats 3i..3i+2).
// load3_component: component `axis` (0..2) of that vector alone, for kernels with an item per axis.
#ifndef MIPNERF_TEST_FAULT
inline float3 load3(__global const float* p, size_t i) { return (float3)(p[3 * i], p[3 * i + 1], p[3 * i + 2]); }
ALWAYS_INLINE float load3_component(__global const float* p, uint i, uint axis) { return p[3 * i + axis]; }
#else
// Test-only, never defined otherwise: `mipnerf-selftest --inject-build-option=-DMIPNERF_TEST_FAULT` stands in for a
// driver with a broken vector load. Every 3-vector read loses the low 8 bits of its mantissas (relative error up to
// 2^-16, far beyond every stage's float32 bound), and the self-test must fail on it.
inline float drop_low_bits(float x) { return as_float(as_uint(x) & 0xFFFFFF00u); }
inline float3 load3(__global const float* p, size_t i) {
  return (float3)(drop_low_bits(p[3 * i]), drop_low_bits(p[3 * i + 1]), drop_low_bits(p[3 * i + 2]));
}
ALWAYS_INLINE float load3_component(__global const float* p, uint i, uint axis) { return drop_low_bits(p[3 * i + axis]); }
#endif
inline void store3(__global float* p, size_t i, float3 v) {
  p[3 * i] = v.x;
  p[3 * i + 1] = v.y;
  p[3 * i + 2] = v.z;
}

// Lanes of the explicit-vector items (float16, uint16): values, samples, groups or rays per item (the host's
// ops::kVectorWidth).
#define VECTOR_WIDTH 16

// STEP(k) for the lanes k = 0 .. f of a 16-wide vector (component .sk), in order, or from the last.
#define FOR_EACH_LANE(STEP) \
  STEP(0) STEP(1) STEP(2) STEP(3) STEP(4) STEP(5) STEP(6) STEP(7) STEP(8) STEP(9) STEP(a) STEP(b) STEP(c) STEP(d) STEP(e) STEP(f)
#define FOR_EACH_LANE_REVERSED(STEP) \
  STEP(f) STEP(e) STEP(d) STEP(c) STEP(b) STEP(a) STEP(9) STEP(8) STEP(7) STEP(6) STEP(5) STEP(4) STEP(3) STEP(2) STEP(1) STEP(0)


#if VECTOR_ITEMS
// Rows at .. at + 15 of a [rows][3] array as three float16 (its interleaved components apart), and back.
ALWAYS_INLINE void load_channels16(__global const float* rgb, uint at, float16* red, float16* green, float16* blue) {
  const float16 a = vload16(0, rgb + 3 * at), b = vload16(0, rgb + 3 * at + 16), c = vload16(0, rgb + 3 * at + 32);
  *red = (float16)(a.s0, a.s3, a.s6, a.s9, a.sc, a.sf, b.s2, b.s5, b.s8, b.sb, b.se, c.s1, c.s4, c.s7, c.sa, c.sd);
  *green = (float16)(a.s1, a.s4, a.s7, a.sa, a.sd, b.s0, b.s3, b.s6, b.s9, b.sc, b.sf, c.s2, c.s5, c.s8, c.sb, c.se);
  *blue = (float16)(a.s2, a.s5, a.s8, a.sb, a.se, b.s1, b.s4, b.s7, b.sa, b.sd, c.s0, c.s3, c.s6, c.s9, c.sc, c.sf);
}

ALWAYS_INLINE void store_channels16(__global float* rgb, uint at, float16 r, float16 g, float16 b) {
  vstore16((float16)(r.s0, g.s0, b.s0, r.s1, g.s1, b.s1, r.s2, g.s2, b.s2, r.s3, g.s3, b.s3, r.s4, g.s4, b.s4, r.s5),
           0, rgb + 3 * at);
  vstore16((float16)(g.s5, b.s5, r.s6, g.s6, b.s6, r.s7, g.s7, b.s7, r.s8, g.s8, b.s8, r.s9, g.s9, b.s9, r.sa, g.sa),
           0, rgb + 3 * at + 16);
  vstore16((float16)(b.sa, r.sb, g.sb, b.sb, r.sc, g.sc, b.sc, r.sd, g.sd, b.sd, r.se, g.se, b.se, r.sf, g.sf, b.sf),
           0, rgb + 3 * at + 32);
}
#endif

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

// One Philox call on four words, in place: counter (c0..c3) in, random words out; for scalar words and for uint16
// (sixteen independent calls lane by lane, the sampler's per-vector items), written once. Scalars where a kernel
// should be vectorised by PoCL across work-items, which cannot widen vector-typed values such as uint4;
// out-parameters rather than a returned struct, whose inlining oclgrind 21.10 cannot run
// (llvm.experimental.noalias.scope.decl). Each 32 x 32 → 64-bit product once, its halves taken apart: the built-in
// mul_hi is a call PoCL does not always inline (its remarks), and a call in the work-item loop stops the vectoriser.
#define DEFINE_PHILOX4X32_10_WORDS(U, W)                                                                        \
  ALWAYS_INLINE OVERLOADABLE void philox4x32_10_words(U* c0, U* c1, U* c2, U* c3, uint k0, uint k1) {           \
    __attribute__((opencl_unroll_hint)) for (int round = 0; round < 10; ++round) {                              \
      const ulong##W product0 = CONVERT_ULONG##W(*c0) * 0xD2511F53UL;                                           \
      const ulong##W product1 = CONVERT_ULONG##W(*c2) * 0xCD9E8D57UL;                                           \
      const U hi0 = CONVERT_UINT##W(product0 >> 32), lo0 = CONVERT_UINT##W(product0 & 0xFFFFFFFFUL);            \
      const U hi1 = CONVERT_UINT##W(product1 >> 32), lo1 = CONVERT_UINT##W(product1 & 0xFFFFFFFFUL);            \
      *c0 = hi1 ^ *c1 ^ k0;                                                                                     \
      *c1 = lo1;                                                                                                \
      *c2 = hi0 ^ *c3 ^ k1;                                                                                     \
      *c3 = lo0;                                                                                                \
      k0 += 0x9E3779B9u;                                                                                        \
      k1 += 0xBB67AE85u;                                                                                        \
    }                                                                                                           \
  }
DEFINE_PHILOX4X32_10_WORDS(uint, )
#if VECTOR_ITEMS
DEFINE_PHILOX4X32_10_WORDS(uint16, 16)
#endif

ALWAYS_INLINE uint4 philox4x32_10(uint4 counter, uint2 key) {
  uint c0 = counter.x, c1 = counter.y, c2 = counter.z, c3 = counter.w;
  philox4x32_10_words(&c0, &c1, &c2, &c3, key.x, key.y);
  return (uint4)(c0, c1, c2, c3);
}

// A uniform float in [0, 1) from one word: its top 24 bits, so every value is exact in float32 and 1.0 is never
// returned.
#define DEFINE_RNG_UNIFORM_OF_WORD(U, V, W)                       \
  ALWAYS_INLINE OVERLOADABLE V rng_uniform_of_word(U word) {      \
    return CONVERT_FLOAT##W(word >> 8) * (1.0f / 16777216.0f);    \
  }
DEFINE_RNG_UNIFORM_OF_WORD(uint, float, )
#if VECTOR_ITEMS
DEFINE_RNG_UNIFORM_OF_WORD(uint16, float16, 16)
#endif

// The four words of rng_uniform4's call (the same counter and key), for rng_uniform_of_word: w0..w3 are set.
ALWAYS_INLINE void rng_words(ulong seed, uint item, uint step, uint slot, uint stream, uint* w0, uint* w1, uint* w2,
                             uint* w3) {
  *w0 = item;
  *w1 = step;
  *w2 = slot;
  *w3 = stream;
  philox4x32_10_words(w0, w1, w2, w3, (uint)seed, (uint)(seed >> 32));
}

// Four uniform floats in [0, 1), rng_uniform_of_word of each word of one call.
ALWAYS_INLINE float4 rng_uniform4(ulong seed, uint item, uint step, uint slot, uint stream) {
  uint w0, w1, w2, w3;
  rng_words(seed, item, step, slot, stream, &w0, &w1, &w2, &w3);
  return (float4)(rng_uniform_of_word(w0), rng_uniform_of_word(w1), rng_uniform_of_word(w2), rng_uniform_of_word(w3));
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

// ---- exp, expm1 and log1p without branches, for the element-wise stages and the render's sample loops ----
// PoCL vectorises a kernel across work-items, but its exp/log1p built-ins keep a slow path for special arguments
// that the whole vector takes when one lane needs it; arithmetic only (fma, rint, bit casts, select) stays in the
// vector units; and a built-in is a call, which keeps PoCL from vectorising the loop it sits in at all. The functions
// cover exactly the arguments the stages give them, with bounds derived here and checked by the stages' tests against
// double references (tests/ops/test_activations.cpp and test_render.cpp sweep every binade).

// Overloads: the element-wise math below is defined for float and for float16, the explicit vectors of the
// per-vector items (activations.cl, render.cl, gaussian.cl). Each such function is written once, in a macro over its value type
// V (float or float16) and W, the width's suffix of the conversion built-ins (empty or 16): the vector version runs
// the same operations lane by lane, so a lane gets the same float, bit for bit, as the scalar version (the tests'
// exact comparisons of fused and separate kernels rely on it). Comments inside the macros are /* */, which a
// continued line cannot end early.

// round_half_even(x): rint(x) for |x| ≤ 2^22 (the reductions below: |x| ≤ 151), as (x + 1.5·2^23) − 1.5·2^23. The
// sum lies in [2^23, 2^24), where floats are the integers, so the addition itself rounds x to the nearest integer,
// ties to even, as rint does in the default rounding mode; the subtraction is exact. (x's product is a separate
// operation before the call, never contracted into the addition.) Why not rint: PoCL 3.1's CPU device emits rint as
// a sequence of conversions, compares and masked adds (no vrndscaleps), several times the cost of two additions. The
// one difference: a result of zero is +0 where rint gives −0 for x in (−0.5, −0]; the callers only multiply it by
// constants and add it to x, where the sign of that zero cannot change a nonzero result.
#define DEFINE_ROUND_HALF_EVEN(V)                                                                      \
  ALWAYS_INLINE OVERLOADABLE V round_half_even(V x) { return (x + 12582912.0f) - 12582912.0f; }
DEFINE_ROUND_HALF_EVEN(float)
#if VECTOR_ITEMS
DEFINE_ROUND_HALF_EVEN(float16)
#endif

// reduce_by_ln2(x, n): x = n·ln2 + r for x ≤ 0 clamped: sets *n = rint(x·log2 e) and returns r, by two fma steps (ln2
// split into its float and the remainder), |r| ≤ ln2/2 + tiny. (An out-parameter, not a returned struct: see
// philox4x32_10_words.)
//
// exp_nonpositive(x): e^x for x ≤ 0 (NaN stays NaN; −∞ gives 0). Cody–Waite: x = n·ln2 + r with n = rint(x·log2 e),
// |r| ≤ ln2/2 + tiny, r from two fma steps (ln2 split into its float and the remainder, so r's error is
// ≤ 2^-24·|r| + 2^-50·|n|); e^r by its Taylor polynomial to r^7 (truncation ≤ (ln2/2)^8/8!·e^0.35 < 8e-9 relative),
// Horner with fma; then ·2^n in two factors 2^⌊n/2⌋·2^(n−⌊n/2⌋), each a normal float, so results down to the
// smallest denormal (x ≥ −103.97) round once as the true value would. Below x = −104 the result is 0
// (e^−104 < 2^−150). Relative error ≤ 3 ulp on normal results (7 roundings of ≤ 2^-24 each in the polynomial, less
// in the reduction). n in [−150, 0] after the clamp, so both factors are ≥ 2^-75.
#define DEFINE_EXP_NONPOSITIVE(V, W)                                                                          \
  ALWAYS_INLINE OVERLOADABLE V reduce_by_ln2(V x, V* n) {                                                     \
    *n = round_half_even(x * 1.44269504f);                                                                    \
    return fma(*n, (V)(-1.90465430e-9f), fma(*n, (V)(-0.693147182f), x));                                     \
  }                                                                                                           \
  ALWAYS_INLINE OVERLOADABLE V exp_nonpositive(V x) {                                                         \
    V n;                                                                                                      \
    const V r = reduce_by_ln2(fmax(x, -104.0f), &n); /* fmax(NaN, c) = c: NaN is restored below */           \
    V p = fma(r, (V)1.98412698e-4f, (V)1.38888889e-3f); /* 1/7!, 1/6! */                                      \
    p = fma(p, r, (V)8.33333333e-3f);                   /* 1/5! */                                            \
    p = fma(p, r, (V)4.16666667e-2f);                   /* 1/4! */                                            \
    p = fma(p, r, (V)1.66666667e-1f);                   /* 1/3! */                                            \
    p = fma(p, r, (V)0.5f);                                                                                   \
    p = fma(p, r, (V)1.0f);                                                                                   \
    p = fma(p, r, (V)1.0f);                                                                                   \
    const int##W n_int = CONVERT_INT##W(n), n_half = n_int / 2;                                              \
    const V scaled = p * as_float##W((n_half + 127) << 23) * as_float##W((n_int - n_half + 127) << 23);       \
    return isnan(x) ? x : scaled;                                                                             \
  }
DEFINE_EXP_NONPOSITIVE(float, )
#if VECTOR_ITEMS
DEFINE_EXP_NONPOSITIVE(float16, 16)
#endif

// expm1_nonpositive(x): e^x − 1 for x ≤ 0 (NaN stays NaN; −∞ gives −1), without the cancellation of exp(x) − 1 near
// 0. The same reduction as exp_nonpositive, x = n·ln2 + r, and e^x − 1 = 2^n·(e^r − 1) + (2^n − 1) with
// e^r − 1 = r + r²·p(r), p the Taylor polynomial to r^8 (truncation ≤ (ln2/2)^7/9!·e^0.35 < 3e-9 relative to
// e^r − 1). For |x| < ln2/2, n = 0 and r = x exactly, so small arguments keep their full relative accuracy; otherwise
// |e^x − 1| ≥ 0.29 and 2^n − 1 is exact (n ≥ −43 after the clamp: 2^n a normal float), so the final fma adds at most
// 1 ulp to the ≤ 2 ulp of e^r − 1 scaled by 2^n ≤ 1/2. Below x = −30 the result is −1 (e^−30 < 2^−25·1: −1 is the
// correctly rounded value). Within 3 ulp by this count; the same formula in C on the host, checked against double
// expm1 at every float in [−40, 0), is within 0.89 ulp. Overloaded as exp_nonpositive is.
#define DEFINE_EXPM1_NONPOSITIVE(V, W)                                                                    \
  ALWAYS_INLINE OVERLOADABLE V expm1_nonpositive(V x) {                                                   \
    V n;                                                                                                  \
    const V r = reduce_by_ln2(fmax(x, -30.0f), &n); /* fmax(NaN, c) = c: NaN is restored below */         \
    V p = fma(r, (V)2.48015873e-5f, (V)1.98412698e-4f); /* 1/8!, 1/7! */                                  \
    p = fma(p, r, (V)1.38888889e-3f);                   /* 1/6! */                                        \
    p = fma(p, r, (V)8.33333333e-3f);                   /* 1/5! */                                        \
    p = fma(p, r, (V)4.16666667e-2f);                   /* 1/4! */                                        \
    p = fma(p, r, (V)1.66666667e-1f);                   /* 1/3! */                                        \
    p = fma(p, r, (V)0.5f);                                                                               \
    const V expm1_r = fma(p * r, r, r);                                                                   \
    const V two_n = as_float##W((CONVERT_INT##W(n) + 127) << 23);                                         \
    const V result = fma(two_n, expm1_r, two_n - 1.0f);                                                   \
    return isnan(x) ? x : result;                                                                         \
  }
DEFINE_EXPM1_NONPOSITIVE(float, )
#if VECTOR_ITEMS
DEFINE_EXPM1_NONPOSITIVE(float16, 16)
#endif

// log1p_unit(y): log(1 + y) for y in [0, 1] (the softplus of exp_nonpositive's results): 2·atanh(s) with
// s = y/(2 + y) in [0, 1/3], an identity with no cancellation, so small y keeps its relative accuracy (s ≈ y/2).
// Series 2s·(1 + s²/3 + … + s^12/13): the terms left out sum to ≤ (1/9)^7/15/(1 − 1/9) < 1.6e-8 relative; with the
// division and 7 fma roundings the result is within 3 ulp. Overloaded as exp_nonpositive is.
#define DEFINE_LOG1P_UNIT(V)                                                  \
  ALWAYS_INLINE OVERLOADABLE V log1p_unit(V y) {                              \
    const V s = y / (2.0f + y), s2 = s * s;                                   \
    V p = fma(s2, (V)7.69230769e-2f, (V)9.09090909e-2f); /* 1/13, 1/11 */     \
    p = fma(p, s2, (V)1.11111111e-1f);                   /* 1/9 */            \
    p = fma(p, s2, (V)1.42857143e-1f);                   /* 1/7 */            \
    p = fma(p, s2, (V)0.2f);                                                  \
    p = fma(p, s2, (V)3.33333333e-1f);                                        \
    p = fma(p, s2, (V)1.0f);                                                  \
    return 2.0f * s * p;                                                      \
  }
DEFINE_LOG1P_UNIT(float)
#if VECTOR_ITEMS
DEFINE_LOG1P_UNIT(float16)
#endif

#endif
