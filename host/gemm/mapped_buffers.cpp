// Mapping device buffers into host memory (see mapped_buffers.hpp).
#include "gemm/mapped_buffers.hpp"

#include <algorithm>

#include "cl/error.hpp"
#include "core/error.hpp"

namespace mipnerf::gemm {

MappedBuffers::~MappedBuffers() {
  for (const Mapping& m : mappings_) {
    if (m.pointer) clEnqueueUnmapMemObject(ctx_.raw_queue(), m.array->raw(), m.pointer, 0, nullptr, nullptr);
  }
}

void MappedBuffers::need(const ocl::DeviceArray<float>* array, bool write) {
  if (array == nullptr) return;
  for (Mapping& m : mappings_) {
    if (m.array->raw() == array->raw()) {
      m.write = m.write || write;
      return;
    }
  }
  mappings_.push_back(Mapping{array, write, nullptr});
}

void MappedBuffers::map() {
  for (Mapping& m : mappings_) {
    cl_int status = CL_SUCCESS;
    const cl_map_flags flags = m.write ? (CL_MAP_READ | CL_MAP_WRITE) : CL_MAP_READ;
    const size_t bytes = std::max<size_t>(1, m.array->size()) * sizeof(float);
    void* p =
        clEnqueueMapBuffer(ctx_.raw_queue(), m.array->raw(), CL_FALSE, flags, 0, bytes, 0, nullptr, nullptr, &status);
    ocl::check(status, "clEnqueueMapBuffer(" + m.array->name() + ") for " + what_);
    m.pointer = p;  // valid once the map has run: after the clFinish below (the destructor unmaps it either way)
  }
  ocl::check(clFinish(ctx_.raw_queue()), "clFinish (the maps of " + what_ + ")");
}

float* MappedBuffers::at(const ocl::DeviceArray<float>* array) const {
  if (array == nullptr) return nullptr;
  for (const Mapping& m : mappings_) {
    if (m.array->raw() == array->raw()) {
      if (m.pointer == nullptr) break;
      return static_cast<float*>(m.pointer);
    }
  }
  throw Error("internal error: " + what_ + " used buffer '" + array->name() + "' that it did not map");
}

}  // namespace mipnerf::gemm
