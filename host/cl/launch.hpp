// Kernel argument setting and padded launches.
#pragma once

#include <string>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "cl/error.hpp"

namespace mipnerf::ocl {

// Rounds n up to a multiple of `multiple` (> 0).
inline size_t round_up(size_t n, size_t multiple) { return (n + multiple - 1) / multiple * multiple; }

namespace detail {
template <typename T>
void set_one(::cl::Kernel& kernel, const std::string& name, cl_uint index, const T& value) {
  check(kernel.setArg(index, value), "clSetKernelArg(" + name + ", arg " + std::to_string(index) + ")");
}
template <typename T>
void set_one(::cl::Kernel& kernel, const std::string& name, cl_uint index, const DeviceArray<T>& array) {
  check(kernel.setArg(index, array.buffer()),
        "clSetKernelArg(" + name + ", arg " + std::to_string(index) + " = " + array.name() + ")");
}
}  // namespace detail

// Sets all arguments of `kernel` in order; a DeviceArray is passed as its buffer.
template <typename... Args>
void set_args(::cl::Kernel& kernel, const std::string& name, const Args&... args) {
  cl_uint index = 0;
  (detail::set_one(kernel, name, index++, args), ...);
}

// Enqueues a 1-D launch over n_items. The global size is padded up to a multiple of the work-group
// size, so kernels must guard with `if (i >= n) return;` (PoCL miscompiles barriers in a partial
// work-group; padding means there never is one). A launch over zero items does nothing.
void launch_1d(Context& ctx, ::cl::Kernel& kernel, size_t n_items, const std::string& name, size_t local_size = 0,
               ::cl::Event* event = nullptr);

// 2-D variant: global sizes padded to multiples of (local_x, local_y).
void launch_2d(Context& ctx, ::cl::Kernel& kernel, size_t n_x, size_t n_y, size_t local_x, size_t local_y,
               const std::string& name, ::cl::Event* event = nullptr);

}  // namespace mipnerf::ocl
