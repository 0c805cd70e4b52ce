// The CPU GEMM libraries the host MLP can run its products on (OpenBLAS, BLIS, oneDNN, libxsmm), behind one
// row-major signature, and which library runs which product.
//
// Each library lives in its own source file under cpu_sgemm/ (their headers clash: OpenBLAS's and BLIS's cblas.h
// declare the same names), compiled only when CMake found the library: one that is not installed is left out and
// listed with the package to install, never a build failure. OpenBLAS is the default for every product.
//
// Which library runs a product is chosen per product shape by measurement (`mipnerf-cl tune` times every library
// built in on the network's products, in the host MLP's thread arrangement, and stores the fastest per shape in the
// device's tuning file; bench_gemm_libs shows all of them). MIPNERF_HOST_GEMM_LIBRARY=<name> runs every product on
// one library (tests and benchmarks).
#pragma once

#include <cstddef>
#include <map>
#include <string>
#include <tuple>
#include <vector>

namespace mipnerf::gemm {

// Row-major C[m][n] = op(A)·op(B) + beta·C (alpha = 1) in the calling thread: op(A) is m×k, op(B) k×n; A is stored
// m×k (k×m when trans_a) with row stride lda, likewise B and C. How the host MLP calls its products.
using RowMajorSgemm = void (*)(bool trans_a, bool trans_b, int m, int n, int k, const float* a, int lda,
                               const float* b, int ldb, float beta, float* c, int ldc);

struct CpuSgemmLibrary {
  std::string name;     // "openblas", "blis", "onednn", "libxsmm"
  std::string version;  // as the library reports it
  std::string threads;  // how it threads, and how a call is held to the calling thread
  RowMajorSgemm sgemm = nullptr;
  // Threads of one call made from the calling thread (1: that thread only). For OpenBLAS and BLIS a process-wide
  // setting, for oneDNN (OpenMP) the calling thread's own: the host MLP calls it in every worker thread.
  void (*set_threads)(int threads) = nullptr;
  // Whether it runs every product (libxsmm 1.17 JIT-compiles no kernel for backward-data products and throws
  // mipnerf::Error for them); a library that does not is only ever chosen for the shapes it ran in tune.
  bool every_shape = true;
};

// The libraries built in, OpenBLAS first (empty without it: then the host backend is not built in either).
const std::vector<CpuSgemmLibrary>& cpu_sgemm_libraries();
// One line per library this build left out: "blis: not built in (install the Debian package libblis-dev)".
std::vector<std::string> cpu_sgemm_libraries_left_out();
// The library of that name; throws mipnerf::Error naming the libraries built in (and what to install) otherwise.
const CpuSgemmLibrary& cpu_sgemm_library(const std::string& name);

// A product's shape as the host MLP calls it, and its label ("forward 256x128x128", "backward_weights 72x128x256":
// kind, then m×n×k), the key of the tuning file's choices.
struct HostProductShape {
  bool trans_a = false, trans_b = false;
  size_t m = 0, n = 0, k = 0;
  bool operator<(const HostProductShape& o) const {
    return std::tie(trans_a, trans_b, m, n, k) < std::tie(o.trans_a, o.trans_b, o.m, o.n, o.k);
  }
};
std::string host_product_label(const HostProductShape& shape);

// Which library runs which product: `by_product` (label → library name) from tune, everything else on `fallback`.
struct HostProductLibraries {
  std::map<std::string, std::string> by_product;
  std::string fallback = "openblas";
};

// The choice resolved to libraries once (names checked: throws mipnerf::Error for a library not built in), then
// looked up per product without allocating. MIPNERF_HOST_GEMM_LIBRARY, when set, overrides every choice.
class HostProductTable {
 public:
  explicit HostProductTable(const HostProductLibraries& choice);
  const CpuSgemmLibrary& library_for(const HostProductShape& shape) const;
  // Every library the table can pick (to hold each to the calling thread in a worker).
  const std::vector<const CpuSgemmLibrary*>& libraries() const { return used_; }

 private:
  std::map<HostProductShape, const CpuSgemmLibrary*> by_shape_;
  const CpuSgemmLibrary* fallback_ = nullptr;
  std::vector<const CpuSgemmLibrary*> used_;
};

// The CPU GEMM library the environment forces (MIPNERF_HOST_GEMM_LIBRARY), or "".
std::string forced_host_gemm_library();

// Each library's entry (defined in cpu_sgemm/<name>.cpp when that library was found).
CpuSgemmLibrary openblas_library();
CpuSgemmLibrary blis_library();
CpuSgemmLibrary onednn_library();
CpuSgemmLibrary libxsmm_library();

}  // namespace mipnerf::gemm
