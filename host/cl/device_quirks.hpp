// Device quirks in one place: per-device build options and launch sizes (CLBlast's pattern).
#pragma once

#include <cstddef>

#include "cl/device.hpp"
#include "cl/program.hpp"

namespace mipnerf::ocl {

struct DeviceTraits {
  // Work-group size for 1-D element-wise kernels; global sizes are padded to a multiple of it.
  size_t local_size_1d = 64;
  // Options every program on this device is built with (e.g. denormal handling).
  BuildOptions base_options;
};

DeviceTraits traits_for(const DeviceInfo& device);

}  // namespace mipnerf::ocl
