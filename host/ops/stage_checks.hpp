// Argument checks shared by the ray-math stage wrappers (rays … activations): sizes before a launch, and the
// kernels' 32-bit counts. Each failure names the stage, the buffer and what to change.
#pragma once

#include <cstddef>
#include <limits>
#include <string>

#include "cl/buffer.hpp"
#include "core/error.hpp"
#include "cl/opencl.hpp"

namespace mipnerf::ops::detail {

// A count as the kernels' uint; throws when it does not fit (the kernels index with 32 bits per launch).
inline cl_uint to_uint(size_t value, const std::string& where, const char* what) {
  if (value > std::numeric_limits<cl_uint>::max()) {
    throw Error(where + ": " + what + " = " + std::to_string(value) +
                " exceeds the kernel's 32-bit count; use smaller chunks of rays");
  }
  return static_cast<cl_uint>(value);
}

// Throws unless `array` holds at least `count` elements.
template <typename T>
void require(const ocl::DeviceArray<T>& array, size_t count, const std::string& where) {
  array.require_size(count, where);
}

}  // namespace mipnerf::ops::detail
