// CPU mirror of kernels/common.cl's counter-based RNG (Philox4x32-10): its uniforms bit for bit, its normal draws in
// double.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

namespace mipnerf {

// RNG streams: one per purpose, so no two uses share numbers (same values as RNG_STREAM_* in common.cl).
enum RngStream : uint32_t { rng_stream_stratified = 0, rng_stream_resample = 1, rng_stream_batch = 2,
                            rng_stream_subpixel = 3, rng_stream_density_noise = 4,
                            rng_stream_multisample = 5, rng_stream_proposal = 6 };

inline std::array<uint32_t, 4> philox4x32_10(std::array<uint32_t, 4> counter, std::array<uint32_t, 2> key) {
  for (int round = 0; round < 10; ++round) {
    const uint64_t product0 = uint64_t{0xD2511F53u} * counter[0];
    const uint64_t product1 = uint64_t{0xCD9E8D57u} * counter[2];
    const uint32_t hi0 = static_cast<uint32_t>(product0 >> 32), lo0 = static_cast<uint32_t>(product0);
    const uint32_t hi1 = static_cast<uint32_t>(product1 >> 32), lo1 = static_cast<uint32_t>(product1);
    counter = {hi1 ^ counter[1] ^ key[0], lo1, hi0 ^ counter[3] ^ key[1], lo0};
    key[0] += 0x9E3779B9u;
    key[1] += 0xBB67AE85u;
  }
  return counter;
}

// Four uniform floats in [0, 1), exactly as rng_uniform4 in common.cl computes them.
inline std::array<float, 4> rng_uniform4(uint64_t seed, uint32_t item, uint32_t step, uint32_t slot,
                                         uint32_t stream) {
  const auto bits = philox4x32_10({item, step, slot, stream},
                                  {static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32)});
  std::array<float, 4> out;
  for (int i = 0; i < 4; ++i) out[i] = static_cast<float>(bits[i] >> 8) * (1.0f / 16777216.0f);
  return out;
}

// Four standard normal draws by the Box–Muller transform of rng_uniform4's four uniforms, as rng_normal4 in common.cl:
// r0·cos(2π·u1), r0·sin(2π·u1), r1·cos(2π·u3), r1·sin(2π·u3) with r_k = sqrt(−2·log(1 − u_{2k})) (1 − u ≥ 2^-24: the
// log is finite). In double from the same float uniforms: the kernel's float32 log, sqrt, cospi and sinpi put its
// draws within a few ulps of these (tests/ops/test_render.cpp bounds the difference), not bit for bit.
inline std::array<double, 4> rng_normal4(uint64_t seed, uint32_t item, uint32_t step, uint32_t slot,
                                         uint32_t stream) {
  constexpr double two_pi = 6.283185307179586476925286766559;
  const auto u = rng_uniform4(seed, item, step, slot, stream);
  const double r0 = std::sqrt(-2.0 * std::log(1.0 - double(u[0]))), r1 = std::sqrt(-2.0 * std::log(1.0 - double(u[2])));
  return {r0 * std::cos(two_pi * u[1]), r0 * std::sin(two_pi * u[1]), r1 * std::cos(two_pi * u[3]),
          r1 * std::sin(two_pi * u[3])};
}

}  // namespace mipnerf
