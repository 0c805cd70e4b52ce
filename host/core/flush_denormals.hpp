// Denormal (subnormal) float32 values flushed to zero in the calling thread while an object lives, then the thread's
// previous setting back.
//
// Why: on x86 an arithmetic instruction that meets or makes a denormal takes a microcode assist, ~100 cycles instead
// of a few. Training drives some values of the host MLP there (gradients of saturated units, products of tiny
// gradients and activations), and the products and element-wise loops slowed step by step: the quick preset's step
// went from 76 to 129 ms over 600 steps on an AVX-512 Xeon, and ran 70 ms flat to the end with denormals flushed
// (bench/results/denormals/denormals.md). What is flushed is below 2^-126 ≈ 1.2e-38 in magnitude, far below anything a
// float32 result of the MLP is compared at; XLA's CPU backend (the official code's) flushes them the same way.
//
// Scope: only the host MLP's worker threads (mlp/host_mlp.cpp) hold one, for the duration of one pass. OpenCL
// kernels keep their runtime's own denormal handling (the kernels' tests check values down to the smallest
// denormal), and the caller's thread gets its setting back when the pass returns.
//
// x86-64: MXCSR's flush-to-zero (results) and denormals-are-zero (inputs) bits. Elsewhere nothing changes.
#pragma once

#if defined(__x86_64__) || defined(__i386__)
#include <xmmintrin.h>
#endif

namespace mipnerf {

class FlushDenormalsInScope {
 public:
#if defined(__x86_64__) || defined(__i386__)
  static constexpr unsigned kFlushToZero = 0x8000u;       // MXCSR.FTZ: a denormal result becomes ±0
  static constexpr unsigned kDenormalsAreZero = 0x0040u;  // MXCSR.DAZ: a denormal input is read as ±0
  // enabled = false: nothing changes (a benchmark's comparison, MIPNERF_KEEP_DENORMALS).
  explicit FlushDenormalsInScope(bool enabled = true) : previous_(_mm_getcsr()) {
    if (enabled) _mm_setcsr(previous_ | kFlushToZero | kDenormalsAreZero);
  }
  ~FlushDenormalsInScope() { _mm_setcsr(previous_); }
  // Whether the calling thread flushes now (tests).
  static bool active() { return (_mm_getcsr() & (kFlushToZero | kDenormalsAreZero)) == (kFlushToZero | kDenormalsAreZero); }

 private:
  unsigned previous_;
#else
  explicit FlushDenormalsInScope(bool = true) {}
  static bool active() { return false; }
#endif

 public:
  FlushDenormalsInScope(const FlushDenormalsInScope&) = delete;
  FlushDenormalsInScope& operator=(const FlushDenormalsInScope&) = delete;
};

}  // namespace mipnerf
