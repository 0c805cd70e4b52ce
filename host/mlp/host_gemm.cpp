// The host GEMM backend: map (blocking), cblas_sgemm, unmap. See host_gemm.hpp for the queue ordering.
#include "mlp/host_gemm.hpp"

#include <algorithm>
#include <vector>

#include "cl/error.hpp"
#include "core/error.hpp"

#ifdef MIPNERF_HAVE_OPENBLAS
#include <cblas.h>
#endif

namespace mipnerf::mlp {
namespace {

// The product's buffers mapped into host memory, each once (A and B may share a buffer; a buffer that is also C is
// mapped for writing). Unmapped by the destructor, so an exception cannot leave a buffer mapped.
class MappedBuffers {
 public:
  MappedBuffers(ocl::Context& ctx, const std::string& what) : ctx_(ctx), what_(what) {}
  ~MappedBuffers() {
    // Enqueued after the BLAS has returned: commands enqueued later run after these unmaps (in-order queue).
    for (const Mapping& m : mappings_)
      clEnqueueUnmapMemObject(ctx_.raw_queue(), m.buffer, m.pointer, 0, nullptr, nullptr);
  }
  MappedBuffers(const MappedBuffers&) = delete;
  MappedBuffers& operator=(const MappedBuffers&) = delete;

  // Records that `view`'s buffer is needed, for writing when `write`. Call for every operand, then map().
  void need(const MatrixView& view, bool write) {
    for (Mapping& m : mappings_) {
      if (m.buffer == view.array->raw()) {
        m.write = m.write || write;
        return;
      }
    }
    mappings_.push_back(Mapping{view.array->raw(), view.array, write, nullptr});
  }

  // Blocking maps of the whole buffers: each returns only when every command enqueued before it has finished.
  void map() {
    for (Mapping& m : mappings_) {
      cl_int status = CL_SUCCESS;
      const cl_map_flags flags = m.write ? (CL_MAP_READ | CL_MAP_WRITE) : CL_MAP_READ;
      const size_t bytes = std::max<size_t>(1, m.array->size()) * sizeof(float);
      void* p = clEnqueueMapBuffer(ctx_.raw_queue(), m.buffer, CL_TRUE, flags, 0, bytes, 0, nullptr, nullptr, &status);
      ocl::check(status, "clEnqueueMapBuffer(" + m.array->name() + ") for host gemm(" + what_ + ")");
      m.pointer = p;
    }
  }

  // The host address of `view`'s first element (after map()).
  float* at(const MatrixView& view) const {
    for (const Mapping& m : mappings_) {
      if (m.buffer == view.array->raw()) return static_cast<float*>(m.pointer) + view.offset;
    }
    throw Error("internal error: host gemm(" + what_ + ") used a buffer it did not map");
  }

 private:
  struct Mapping {
    cl_mem buffer;
    const ocl::DeviceArray<float>* array;
    bool write;
    void* pointer;
  };
  ocl::Context& ctx_;
  std::string what_;
  std::vector<Mapping> mappings_;
};

}  // namespace

#ifdef MIPNERF_HAVE_OPENBLAS

void host_gemm(ocl::Context& ctx, const GemmShape& s, float alpha, const MatrixView& a, const MatrixView& b, float beta,
               const MatrixView& c, const std::string& what) {
  MappedBuffers mapped(ctx, what);
  mapped.need(a, false);
  mapped.need(b, false);
  mapped.need(c, true);
  mapped.map();  // from here until `mapped` is destroyed, no device command touches these buffers
  cblas_sgemm(CblasRowMajor, s.transpose_a ? CblasTrans : CblasNoTrans, s.transpose_b ? CblasTrans : CblasNoTrans,
              static_cast<int>(s.m), static_cast<int>(s.n), static_cast<int>(s.k), alpha, mapped.at(a),
              static_cast<int>(a.ld), mapped.at(b), static_cast<int>(b.ld), beta, mapped.at(c), static_cast<int>(c.ld));
}

void set_host_blas_threads(int threads) { openblas_set_num_threads(threads); }

#else

void host_gemm(ocl::Context&, const GemmShape&, float, const MatrixView&, const MatrixView&, float, const MatrixView&,
               const std::string& what) {
  throw Error("gemm(" + what +
              "): this build has no host BLAS; install libopenblas-dev and rebuild, or use "
              "gemm_backend=clblast");
}

void set_host_blas_threads(int) {}

#endif

}  // namespace mipnerf::mlp
