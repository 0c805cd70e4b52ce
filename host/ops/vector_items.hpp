// Which devices the ray-math stages give explicit 16-wide items by default (the kernels' *_PER_VECTOR switches and
// ACTIVATION_ITEMS = per vector): PoCL's CPU device, which runs an item's float16 code as written in full-width
// vector registers, where its own vectorisation across items ran the same stages 8 wide with long dependent chains or
// through 4-wide gathers (bench/results/kernel_runtimes/kernel_runtimes_xeon.md). Other devices keep their items.
#pragma once

#include <cstddef>

#include "cl/context.hpp"

namespace mipnerf::ops {

constexpr size_t kVectorWidth = 16;  // lanes per explicit-vector item: VECTOR_WIDTH of common.cl (float16, uint16)

inline bool explicit_vector_items(const ocl::Context& ctx) {
  const auto& device = ctx.device_info();
  return (device.type & CL_DEVICE_TYPE_CPU) != 0 && device.is_pocl();
}

// `asked` unless it is Items::device_default; then `vector_items` where explicit_vector_items, else `otherwise`.
template <typename Items>
Items items_for_device(const ocl::Context& ctx, Items asked, Items vector_items, Items otherwise) {
  if (asked != Items::device_default) return asked;
  return explicit_vector_items(ctx) ? vector_items : otherwise;
}

}  // namespace mipnerf::ops
