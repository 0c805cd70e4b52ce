// Packing cameras and their lens tables onto the device, once per camera set.
#include "data/device_cameras.hpp"

#include <algorithm>

#include "core/error.hpp"
#include "data/lens_tables.hpp"

namespace mipnerf::data {

DeviceCameras::DeviceCameras(ocl::Context& ctx, const std::vector<Camera>& cameras,
                             const std::vector<std::string>& names, const std::string& label)
    : count_(cameras.size()) {
  if (cameras.empty()) throw Error(label + ": no camera to upload");
  auto packed = pack_cameras(cameras);
  // Cameras behind a lens: their rays and radii come from tables made once here (data/lens_tables.hpp).
  const LensTables tables = build_lens_tables(cameras, names);
  set_lens_table_slots(packed, tables);
  packed_ = ocl::DeviceArray<float>(ctx, packed.size(), "cameras [C][24] of " + label);
  packed_.upload(ctx, packed);
  has_lens_tables_ = !tables.empty();
  lens_tables_ = ocl::DeviceArray<float>(ctx, has_lens_tables_ ? tables.values.size() : 4,
                                         "lens tables [pixels][4] of " + label);
  if (has_lens_tables_) lens_tables_.upload(ctx, tables.values);
}

size_t DeviceCameras::packed_bytes(size_t count) { return count * camera_layout::stride * sizeof(float); }

}  // namespace mipnerf::data
