// Uploading a split to the device.
#include "data/device_dataset.hpp"

#include <algorithm>

#include "core/error.hpp"

namespace mipnerf::data {

namespace {
// The split, once it is known to fit the device's 32-bit pixel indices and to hold an image.
const Split& uploadable(const Split& split) {
  if (split.cameras.empty()) throw Error("split '" + split.name + "' has no images to upload");
  if (split.num_pixels() >= (uint64_t{1} << 32)) {
    throw Error("split '" + split.name + "' has " + std::to_string(split.num_pixels()) +
                " pixels; the device indexes pixels with 32 bits: use fewer images or a lower resolution");
  }
  return split;
}
}  // namespace

DeviceDataset::DeviceDataset(ocl::Context& ctx, const Split& split)
    : host_cameras_(uploadable(split).cameras),
      num_pixels_(split.num_pixels()),
      cameras_(ctx, split.cameras, split.files, split.name) {
  pixels_rgb_ = ocl::DeviceArray<float>(ctx, split.rgb.size(), "pixels_rgb [pixels][3] of " + split.name);
  pixels_rgb_.upload(ctx, split.rgb);
  std::vector<uint32_t> offsets(split.pixel_offsets.begin(), split.pixel_offsets.end());
  pixel_offsets_ = ocl::DeviceArray<uint32_t>(ctx, offsets.size(), "pixel_offsets [C+1] of " + split.name);
  pixel_offsets_.upload(ctx, offsets);
}

size_t DeviceDataset::bytes_for(const Split& split) {
  return DeviceCameras::packed_bytes(split.cameras.size()) + split.rgb.size() * sizeof(float) +
         split.pixel_offsets.size() * sizeof(uint32_t);
}

size_t DeviceDataset::largest_buffer_for(const Split& split) {
  return std::max({DeviceCameras::packed_bytes(split.cameras.size()), split.rgb.size() * sizeof(float),
                   split.pixel_offsets.size() * sizeof(uint32_t)});
}

}  // namespace mipnerf::data
