// Allocation flags and checks for device arrays.
#include "cl/buffer.hpp"

namespace mipnerf::ocl {

cl_mem_flags allocation_flags(const Context& ctx) {
  return CL_MEM_READ_WRITE | (ctx.device_info().host_unified_memory ? CL_MEM_ALLOC_HOST_PTR : 0);
}

void check_allocation(const Context& ctx, size_t bytes, const std::string& name) {
  const auto& device = ctx.device_info();
  if (device.max_alloc_bytes != 0 && bytes > device.max_alloc_bytes) {
    throw Error("buffer '" + name + "' needs " + std::to_string(bytes >> 20) + " MiB but '" + device.name +
                "' allows at most " + std::to_string(device.max_alloc_bytes >> 20) +
                " MiB per allocation: lower batch_size or chunk_rays (training), --chunk or render_chunk_rays (rendering)");
  }
}

}  // namespace mipnerf::ocl
