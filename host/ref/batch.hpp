// CPU mirror of kernels/batch.cl: the training batch of a step, the same Philox words, the same integers.
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/camera.hpp"
#include "core/rng.hpp"

namespace mipnerf::ref {

// floor(bits · n / 2^64) with bits = hi_word·2^32 + lo_word, as uniform_below in batch.cl.
inline uint64_t uniform_below(uint32_t hi_word, uint32_t lo_word, uint64_t n) {
  const unsigned __int128 bits = (static_cast<uint64_t>(hi_word) << 32) | lo_word;
  return static_cast<uint64_t>((bits * n) >> 64);
}

// Mirrors batch_sample (arguments in the kernel's order; single_image = BATCH_SINGLE_IMAGE).
// pixel_offsets [num_cameras + 1], pixels_rgb [pixels][3], cameras [C][24] (camera_layout);
// writes camera_ids [n], pixel_ids [n], target_rgb [n][3], lossmult [n].
inline void batch_sample(uint64_t seed, uint32_t step, const uint32_t* pixel_offsets, uint32_t num_cameras,
                         const float* pixels_rgb, const float* cameras, uint32_t* camera_ids, uint32_t* pixel_ids,
                         float* target_rgb, float* lossmult, uint32_t n_rays, bool single_image) {
  const std::array<uint32_t, 2> key{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32)};
  const auto image_words = philox4x32_10({0u, step, 1u, rng_stream_batch}, key);
  for (uint32_t i = 0; i < n_rays; ++i) {
    const auto words = philox4x32_10({i, step, 0u, rng_stream_batch}, key);
    uint32_t camera = 0, global_pixel = 0;
    if (single_image) {
      camera = static_cast<uint32_t>(uniform_below(image_words[0], image_words[1], num_cameras));
      const uint32_t first = pixel_offsets[camera];
      global_pixel = first + static_cast<uint32_t>(uniform_below(words[0], words[1], pixel_offsets[camera + 1] - first));
    } else {
      global_pixel = static_cast<uint32_t>(uniform_below(words[0], words[1], pixel_offsets[num_cameras]));
      while (camera + 1 < num_cameras && pixel_offsets[camera + 1] <= global_pixel) ++camera;  // linear: an oracle
    }
    camera_ids[i] = camera;
    pixel_ids[i] = global_pixel - pixel_offsets[camera];
    for (int c = 0; c < 3; ++c) target_rgb[3 * static_cast<size_t>(i) + c] = pixels_rgb[3 * static_cast<size_t>(global_pixel) + c];
    lossmult[i] = cameras[static_cast<size_t>(camera) * camera_layout::stride + camera_layout::lossmult];
  }
}

}  // namespace mipnerf::ref
