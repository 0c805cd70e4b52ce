// CPU mirror of kernels/common.cl's counter-based RNG (Philox4x32-10), bit for bit.
#pragma once

#include <array>
#include <cstdint>

namespace mipnerf {

// RNG streams: one per purpose, so no two uses share numbers (same values as RNG_STREAM_* in common.cl).
enum RngStream : uint32_t { rng_stream_stratified = 0, rng_stream_resample = 1, rng_stream_batch = 2,
                            rng_stream_subpixel = 3 };

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

}  // namespace mipnerf
