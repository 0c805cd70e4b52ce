// The CPU device a self-test compares training steps with: another device than the one tested.
#pragma once

#include <optional>

#include "cl/device.hpp"

namespace mipnerf::selftest {

// The first CPU device of the machine on another platform or at another index than `tested`, if any.
inline std::optional<ocl::DeviceInfo> other_cpu_device(const ocl::DeviceInfo& tested) {
  for (const auto& d : ocl::list_devices()) {
    if ((d.type & CL_DEVICE_TYPE_CPU) && d.index != tested.index) return d;
  }
  return std::nullopt;
}

}  // namespace mipnerf::selftest
