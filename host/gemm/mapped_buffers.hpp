// Device buffers mapped into host memory for work the host does on them (the host GEMM backend, the host MLP), each
// buffer once, unmapped when the object dies, so an exception cannot leave a buffer mapped.
//
// Queue ordering (what makes host work safe beside the device's kernels on one in-order queue): map() enqueues every
// buffer's map and then waits for the queue to finish (clFinish), so it returns only after every command enqueued
// before it, the maps included, has finished; the host then works while nothing else is enqueued (one host thread
// drives the queue); the destructor enqueues the unmaps, and commands enqueued afterwards start only after them, so
// they see what the host wrote. (One wait, not a blocking map per buffer: on PoCL's CPU device each blocking map was
// a round trip to its worker thread, ~12 per MLP call, 35 % of a tiny-preset step.)
#pragma once

#include <string>
#include <vector>

#include "cl/buffer.hpp"
#include "cl/context.hpp"

namespace mipnerf::gemm {

class MappedBuffers {
 public:
  MappedBuffers(ocl::Context& ctx, std::string what) : ctx_(ctx), what_(std::move(what)) {}
  ~MappedBuffers();
  MappedBuffers(const MappedBuffers&) = delete;
  MappedBuffers& operator=(const MappedBuffers&) = delete;

  // Records that `array` is needed, for writing when `write`. Call for every buffer, then map(). A null array (an
  // empty view) is ignored.
  void need(const ocl::DeviceArray<float>* array, bool write);
  void need(const ocl::MatrixView& view, bool write) { need(view.array, write); }

  void map();  // maps the whole buffers, then waits for the queue to finish

  // The host address of `array`'s first element, or of `view`'s (after map()); nullptr for a null array.
  float* at(const ocl::DeviceArray<float>* array) const;
  float* at(const ocl::MatrixView& view) const {
    float* base = at(view.array);
    return base ? base + view.offset : nullptr;
  }

 private:
  struct Mapping {
    const ocl::DeviceArray<float>* array;
    bool write;
    void* pointer;
  };
  ocl::Context& ctx_;
  std::string what_;
  std::vector<Mapping> mappings_;
};

}  // namespace mipnerf::gemm
