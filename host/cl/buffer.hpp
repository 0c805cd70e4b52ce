// Typed device arrays: an OpenCL buffer that knows its element type, count and name (for error messages).
#pragma once

#include <algorithm>
#include <string>
#include <vector>

#include "cl/context.hpp"
#include "cl/error.hpp"

namespace mipnerf::ocl {

// An event for the stage profiler when it records (profiler.hpp), else nullptr.
inline ::cl::Event* profiler_event(Context& ctx) {
  return ctx.recording_profiler() ? ctx.recording_profiler()->next_event() : nullptr;
}

// CL_MEM_READ_WRITE, plus CL_MEM_ALLOC_HOST_PTR on devices that share host memory: there the buffer is allocated
// where the host can reach it, so clEnqueueMapBuffer returns a pointer to the buffer itself instead of a copy (the
// host GEMM backend, mlp/host_gemm.cpp, runs the CPU BLAS on such pointers).
cl_mem_flags allocation_flags(const Context& ctx);

// Throws when `bytes` exceeds the device's single-allocation limit, naming the buffer and what to lower.
void check_allocation(const Context& ctx, size_t bytes, const std::string& name);

template <typename T>
class DeviceArray {
 public:
  DeviceArray() = default;
  // `name` should say what the buffer holds and its layout, e.g. "means [rays][samples][3]".
  DeviceArray(Context& ctx, size_t count, std::string name) : count_(count), name_(std::move(name)) {
    // OpenCL refuses zero-sized buffers; an empty array still owns one element's worth.
    const size_t bytes = std::max<size_t>(1, count) * sizeof(T);
    check_allocation(ctx, bytes, name_);
    cl_int status = CL_SUCCESS;
    buffer_ = ::cl::Buffer(ctx.context(), allocation_flags(ctx), bytes, nullptr, &status);
    check(status, "clCreateBuffer(" + name_ + ", " + std::to_string(bytes) + " bytes)");
  }

  size_t size() const { return count_; }
  size_t bytes() const { return count_ * sizeof(T); }
  const std::string& name() const { return name_; }
  const ::cl::Buffer& buffer() const { return buffer_; }
  cl_mem raw() const { return buffer_(); }
  bool allocated() const { return buffer_() != nullptr; }

  // Blocking copies. `offset` and `count` are in elements.
  void upload(Context& ctx, const T* data, size_t count, size_t offset = 0) {
    require_range(offset, count, "upload");
    if (count == 0) return;
    check(ctx.queue().enqueueWriteBuffer(buffer_, CL_TRUE, offset * sizeof(T), count * sizeof(T), data),
          "clEnqueueWriteBuffer(" + name_ + ")");
  }
  void upload(Context& ctx, const std::vector<T>& data) { upload(ctx, data.data(), data.size()); }

  void download(Context& ctx, T* data, size_t count, size_t offset = 0) const {
    require_range(offset, count, "download");
    if (count == 0) return;
    check(ctx.queue().enqueueReadBuffer(buffer_, CL_TRUE, offset * sizeof(T), count * sizeof(T), data),
          "clEnqueueReadBuffer(" + name_ + ")");
  }
  std::vector<T> download(Context& ctx) const {
    std::vector<T> out(count_);
    download(ctx, out.data(), count_);
    return out;
  }

  // Sets every element to `value` (asynchronous, in queue order).
  void fill(Context& ctx, T value) {
    if (count_ == 0) return;
    check(ctx.queue().enqueueFillBuffer(buffer_, value, 0, bytes(), nullptr, profiler_event(ctx)),
          "clEnqueueFillBuffer(" + name_ + ")");
  }

  // Throws unless the array holds at least `count` elements; `where` names the caller.
  void require_size(size_t count, const std::string& where) const {
    if (count_ < count) {
      throw Error(where + ": buffer '" + name_ + "' holds " + std::to_string(count_) + " elements, needs " +
                  std::to_string(count));
    }
  }

 private:
  void require_range(size_t offset, size_t count, const char* what) const {
    if (offset + count > count_) {
      throw Error(std::string(what) + " of " + std::to_string(count) + " elements at " + std::to_string(offset) +
                  " overruns buffer '" + name_ + "' of " + std::to_string(count_));
    }
  }

  ::cl::Buffer buffer_;
  size_t count_ = 0;
  std::string name_;
};

// Enqueues dst[dst_offset .. + count) = src[src_offset .. + count) on the device (asynchronous, in queue
// order); offsets and count in elements, both ranges checked.
template <typename T>
void copy(Context& ctx, const DeviceArray<T>& src, size_t src_offset, DeviceArray<T>& dst, size_t dst_offset,
          size_t count) {
  if (count == 0) return;
  src.require_size(src_offset + count, "copy from");
  dst.require_size(dst_offset + count, "copy to");
  check(ctx.queue().enqueueCopyBuffer(src.buffer(), dst.buffer(), src_offset * sizeof(T), dst_offset * sizeof(T),
                                      count * sizeof(T), nullptr, profiler_event(ctx)),
        "clEnqueueCopyBuffer(" + src.name() + " -> " + dst.name() + ")");
}

// A row-major matrix inside a device buffer: element (r, c) is at buffer[offset + r·ld + c].
struct MatrixView {
  const ocl::DeviceArray<float>* array = nullptr;
  size_t offset = 0;  // in elements
  size_t ld = 0;      // leading dimension: elements between consecutive rows
};

inline MatrixView view(const ocl::DeviceArray<float>& array, size_t ld, size_t offset = 0) {
  return MatrixView{&array, offset, ld};
}

// Throws mipnerf::Error (naming `where`, `which` and the buffer) unless `v` holds a rows×cols matrix: a buffer, a
// leading dimension of at least cols, and room for its last row. Every product and every network call checks its
// matrices with it before any backend reads or writes them.
inline void require_matrix(const MatrixView& v, size_t rows, size_t cols, const char* which, const std::string& where) {
  if (v.array == nullptr) throw Error(where + ": matrix " + which + " has no buffer");
  if (v.ld < cols) {
    throw Error(where + ": matrix " + which + " has leading dimension " + std::to_string(v.ld) + " < its " +
                std::to_string(cols) + " columns");
  }
  const size_t span = rows == 0 ? 0 : (rows - 1) * v.ld + cols;
  v.array->require_size(v.offset + span, where + " matrix " + which);
}

}  // namespace mipnerf::ocl
