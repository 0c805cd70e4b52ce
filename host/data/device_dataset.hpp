// A split on the device: its cameras and all its pixels (every image, every scale), uploaded once. Rays are
// generated on the device from the cameras (kernels/rays.cl) for the pixels a batch picks (ops/batch.hpp);
// no per-pixel ray is ever stored on the host.
#pragma once

#include <cstdint>
#include <vector>

#include "cl/buffer.hpp"
#include "data/dataset.hpp"
#include "data/device_cameras.hpp"

namespace mipnerf::data {

class DeviceDataset {
 public:
  // Uploads `split` (its cameras with their lens tables, data/device_cameras.hpp). Throws mipnerf::Error when it has no image, or 2^32 pixels or more (pixel indices are
  // 32-bit on the device), or a buffer exceeds the device's allocation limit.
  DeviceDataset(ocl::Context& ctx, const Split& split);

  // Bytes the device arrays of `split` take (cameras [C][camera_layout::stride], pixels, offsets), for memory plans.
  static size_t bytes_for(const Split& split);
  // The biggest of those arrays (the pixels, but for a split of a handful of pixels), for the allocation limit.
  static size_t largest_buffer_for(const Split& split);

  uint32_t num_cameras() const { return static_cast<uint32_t>(host_cameras_.size()); }
  uint64_t num_pixels() const { return num_pixels_; }
  const std::vector<Camera>& host_cameras() const { return host_cameras_; }

  const DeviceCameras& cameras() const { return cameras_; }  // packed [C][24], and lens tables when any lens
  const ocl::DeviceArray<float>& pixels_rgb() const { return pixels_rgb_; }      // [pixels][3]
  const ocl::DeviceArray<uint32_t>& pixel_offsets() const { return pixel_offsets_; }  // [C + 1]

 private:
  std::vector<Camera> host_cameras_;
  uint64_t num_pixels_ = 0;
  DeviceCameras cameras_;
  ocl::DeviceArray<float> pixels_rgb_;
  ocl::DeviceArray<uint32_t> pixel_offsets_;
};

}  // namespace mipnerf::data
