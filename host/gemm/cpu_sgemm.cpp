// Which CPU GEMM libraries this build has (CMakeLists.txt defines MIPNERF_HAVE_<NAME> for each one found), and the
// per-product choice among them.
#include "gemm/cpu_sgemm.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "core/error.hpp"

namespace mipnerf::gemm {
namespace {

std::vector<CpuSgemmLibrary> build_list() {
  std::vector<CpuSgemmLibrary> libraries;
#ifdef MIPNERF_HAVE_OPENBLAS
  libraries.push_back(openblas_library());
#endif
#ifdef MIPNERF_HAVE_BLIS
  libraries.push_back(blis_library());
#endif
#ifdef MIPNERF_HAVE_ONEDNN
  libraries.push_back(onednn_library());
#endif
#ifdef MIPNERF_HAVE_LIBXSMM
  libraries.push_back(libxsmm_library());
#endif
  return libraries;
}

std::string names_built_in() {
  std::string names;
  for (const auto& library : cpu_sgemm_libraries()) names += (names.empty() ? "" : ", ") + library.name;
  return names.empty() ? "none" : names;
}

}  // namespace

const std::vector<CpuSgemmLibrary>& cpu_sgemm_libraries() {
  static const std::vector<CpuSgemmLibrary> libraries = build_list();
  return libraries;
}

std::vector<std::string> cpu_sgemm_libraries_left_out() {
  std::vector<std::string> lines;
#ifndef MIPNERF_HAVE_OPENBLAS
  lines.push_back("openblas: not built in (install the Debian package libopenblas-dev, then rebuild)");
#endif
#ifndef MIPNERF_HAVE_BLIS
  lines.push_back("blis: not built in (install the Debian package libblis-dev, then rebuild)");
#endif
#ifndef MIPNERF_HAVE_ONEDNN
  lines.push_back("onednn: not built in (install the Debian package libdnnl-dev, then rebuild)");
#endif
#ifndef MIPNERF_HAVE_LIBXSMM
  lines.push_back("libxsmm: not built in (install the Debian package libxsmm-dev, then rebuild)");
#endif
  return lines;
}

const CpuSgemmLibrary& cpu_sgemm_library(const std::string& name) {
  for (const auto& library : cpu_sgemm_libraries()) {
    if (library.name == name) return library;
  }
  std::string hint;
  for (const auto& line : cpu_sgemm_libraries_left_out()) {
    if (line.rfind(name + ":", 0) == 0) hint = " (" + line + ")";
  }
  throw Error("CPU GEMM library '" + name + "' is not built in" + hint + "; built in: " + names_built_in());
}

std::string host_product_label(const HostProductShape& s) {
  std::ostringstream label;
  label << (s.trans_a ? "backward_weights" : s.trans_b ? "backward_data" : "forward") << ' ' << s.m << 'x' << s.n
        << 'x' << s.k;
  if (s.trans_a && s.trans_b) label << " (both transposed)";
  return label.str();
}

std::string forced_host_gemm_library() {
  const char* forced = std::getenv("MIPNERF_HOST_GEMM_LIBRARY");
  return forced ? forced : "";
}

HostProductTable::HostProductTable(const HostProductLibraries& choice) {
  const std::string forced = forced_host_gemm_library();
  auto use_for_all = [&](const std::string& name, const char* why) {
    const CpuSgemmLibrary& library = cpu_sgemm_library(name);
    if (!library.every_shape) {
      throw Error("CPU GEMM library '" + name + "' " + why + ", but it cannot run every product (" + library.threads +
                  "); name one that can, e.g. openblas");
    }
  };
  auto use = [&](const std::string& name) {
    const CpuSgemmLibrary* library = &cpu_sgemm_library(name);
    if (std::find(used_.begin(), used_.end(), library) == used_.end()) used_.push_back(library);
    return library;
  };
  if (!forced.empty()) {
    use_for_all(forced, "is forced by MIPNERF_HOST_GEMM_LIBRARY for every product");
    fallback_ = use(forced);
    return;
  }
  if (cpu_sgemm_libraries().empty()) return;  // no host BLAS: HostMlp refuses its first product
  use_for_all(choice.fallback, "is the fallback for products without a choice");
  fallback_ = use(choice.fallback);
  for (const auto& [label, name] : choice.by_product) {
    // Labels are parsed back into shapes so the per-product lookup compares numbers, not strings.
    HostProductShape shape;
    char kind[32] = {0};
    unsigned long m = 0, n = 0, k = 0;
    if (std::sscanf(label.c_str(), "%31s %lux%lux%lu", kind, &m, &n, &k) != 4) {
      throw Error("host product choice '" + label + "': not a product label such as 'forward 256x128x128'");
    }
    const std::string kind_name = kind;
    shape.trans_a = kind_name == "backward_weights";
    shape.trans_b = kind_name == "backward_data";
    if (!shape.trans_a && !shape.trans_b && kind_name != "forward") {
      throw Error("host product choice '" + label + "': kind '" + kind_name +
                  "' is none of forward, backward_data, backward_weights");
    }
    shape.m = m, shape.n = n, shape.k = k;
    by_shape_[shape] = use(name);
  }
}

const CpuSgemmLibrary& HostProductTable::library_for(const HostProductShape& shape) const {
  if (!by_shape_.empty()) {
    const auto found = by_shape_.find(shape);
    if (found != by_shape_.end()) return *found->second;
  }
  if (fallback_ == nullptr) throw Error("host MLP: this build has no CPU GEMM library (install libopenblas-dev)");
  return *fallback_;
}

}  // namespace mipnerf::gemm
