// Lookup of embedded kernel files by name.
#include "cl/kernel_sources.hpp"

#include "cl/error.hpp"

namespace mipnerf::ocl {

std::string_view kernel_source(const std::string& name) {
  std::string known;
  for (const auto& file : embedded_kernel_files()) {
    if (name == file.name) return file.text;
    known += known.empty() ? "" : ", ";
    known += file.name;
  }
  throw Error("no embedded kernel file '" + name + "' (embedded: " + known + "); re-run cmake after adding a .cl file");
}

}  // namespace mipnerf::ocl
