// Uploading a split to the device.
#include "data/device_dataset.hpp"

#include <algorithm>

#include "core/error.hpp"
#include "data/lens_tables.hpp"

namespace mipnerf::data {

DeviceDataset::DeviceDataset(ocl::Context& ctx, const Split& split)
    : host_cameras_(split.cameras), num_pixels_(split.num_pixels()) {
  if (split.cameras.empty()) throw Error("split '" + split.name + "' has no images to upload");
  if (num_pixels_ >= (uint64_t{1} << 32)) {
    throw Error("split '" + split.name + "' has " + std::to_string(num_pixels_) +
                " pixels; the device indexes pixels with 32 bits: use fewer images or a lower resolution");
  }
  auto packed = pack_cameras(split.cameras);
  // Cameras behind a lens: their rays and radii come from tables made once here (data/lens_tables.hpp).
  const LensTables tables = build_lens_tables(split.cameras, split.files);
  set_lens_table_slots(packed, tables);
  cameras_ = ocl::DeviceArray<float>(ctx, packed.size(), "cameras [C][24] of " + split.name);
  cameras_.upload(ctx, packed);
  if (!tables.empty()) {
    lens_tables_ = ocl::DeviceArray<float>(ctx, tables.values.size(), "lens tables [pixels][4] of " + split.name);
    lens_tables_.upload(ctx, tables.values);
    has_lens_tables_ = true;
  }
  pixels_rgb_ = ocl::DeviceArray<float>(ctx, split.rgb.size(), "pixels_rgb [pixels][3] of " + split.name);
  pixels_rgb_.upload(ctx, split.rgb);
  std::vector<uint32_t> offsets(split.pixel_offsets.begin(), split.pixel_offsets.end());
  pixel_offsets_ = ocl::DeviceArray<uint32_t>(ctx, offsets.size(), "pixel_offsets [C+1] of " + split.name);
  pixel_offsets_.upload(ctx, offsets);
}

size_t DeviceDataset::bytes_for(const Split& split) {
  return split.cameras.size() * camera_layout::stride * sizeof(float) + split.rgb.size() * sizeof(float) +
         split.pixel_offsets.size() * sizeof(uint32_t);
}

size_t DeviceDataset::largest_buffer_for(const Split& split) {
  return std::max({split.cameras.size() * camera_layout::stride * sizeof(float), split.rgb.size() * sizeof(float),
                   split.pixel_offsets.size() * sizeof(uint32_t)});
}

}  // namespace mipnerf::data
