// Training-batch sampling on the device (kernels/batch.cl): where batch_sample's arguments are set.
#pragma once

#include <array>
#include <cstdint>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "core/enum_names.hpp"
#include "data/device_dataset.hpp"

namespace mipnerf::ops {

enum class Batching {
  all_images,   // every ray picks a pixel uniformly among all pixels of the split (the paper's default)
  single_image  // one image per step, pixels uniform in it
};
// The names of TrainConfig::batching (train/config parses them).
constexpr std::array<EnumName<Batching>, 2> enum_names(Batching) {
  return {{{Batching::all_images, "all_images"}, {Batching::single_image, "single_image"}}};
}

struct BatchOptions {
  uint64_t seed = 0;  // with the step, decides every choice (RNG_STREAM_BATCH)
  Batching batching = Batching::all_images;
};

// The arrays one training step's batch fills, R = rays.
struct BatchArrays {
  BatchArrays() = default;
  BatchArrays(ocl::Context& ctx, size_t rays);
  // Bytes the four arrays take for `rays` rays, for memory plans.
  static size_t bytes_for(size_t rays);
  size_t rays = 0;
  ocl::DeviceArray<uint32_t> camera_ids;  // [R] index into the split's cameras
  ocl::DeviceArray<uint32_t> pixel_ids;   // [R] y·width + x in that image
  ocl::DeviceArray<float> target_rgb;     // [R][3] the pixel's composited colour
  ocl::DeviceArray<float> lossmult;       // [R] the camera's lossmult (1, 4, 16, 64 for multiscale scales)
};

// Fills `batch` (all batch.rays rays) for training step `step`. Asynchronous (in queue order).
void batch_sample(ocl::Context& ctx, const data::DeviceDataset& dataset, const BatchOptions& options, uint32_t step,
                  BatchArrays& batch);

}  // namespace mipnerf::ops
