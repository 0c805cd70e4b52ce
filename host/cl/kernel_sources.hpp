// Access to the kernels/*.cl files embedded into the library at build time.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace mipnerf::ocl {

struct EmbeddedKernelFile {
  const char* name;       // file name inside kernels/, e.g. "render.cl"
  std::string_view text;  // its full text
};

// Defined in the generated embedded_kernels.cpp (cmake/embed_kernels_script.cmake).
const std::vector<EmbeddedKernelFile>& embedded_kernel_files();

// The text of kernels/<name>; throws mipnerf::Error listing the embedded files when absent.
std::string_view kernel_source(const std::string& name);

}  // namespace mipnerf::ocl
