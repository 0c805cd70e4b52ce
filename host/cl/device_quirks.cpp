// Device quirks in one place: per-device build options and launch sizes.
#include "cl/device_quirks.hpp"

#include <algorithm>

namespace mipnerf::ocl {

DeviceTraits traits_for(const DeviceInfo& device) {
  DeviceTraits traits;
  if (device.is_pocl()) {
    // PoCL turns a work-group into a loop over its items and vectorises across them; 64 items give
    // the vectoriser whole AVX2 lanes while keeping per-group overhead small. PoCL also mishandles
    // barriers in a partial work-group, which is why every launch pads the global size (launch.hpp).
    traits.local_size_1d = 64;
  } else if (device.type & CL_DEVICE_TYPE_GPU) {
    traits.local_size_1d = 128;
  }
  traits.local_size_1d = std::min(traits.local_size_1d, std::max<size_t>(1, device.max_work_group_size));
  // Every program identifies the device class, so kernels can specialise a quirk in code if needed.
  traits.base_options.define("MIPNERF_DEVICE_IS_CPU", (device.type & CL_DEVICE_TYPE_CPU) ? 1 : 0);
  return traits;
}

}  // namespace mipnerf::ocl
