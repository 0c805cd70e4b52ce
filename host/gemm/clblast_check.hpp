// CLBlast status names and the check that turns a failed CLBlast call into a mipnerf::Error.
#pragma once

#include <string>

#include <clblast.h>

namespace mipnerf::gemm {

// "kInsufficientMemoryC" for -1009; OpenCL codes shared with CLBlast give their CL_ name.
std::string clblast_status_name(clblast::StatusCode status);

// Throws mipnerf::Error naming the call (e.g. "clblast::Gemm(layer 3 forward, 4096x256x256)") and the status.
void check_clblast(clblast::StatusCode status, const std::string& call);

// "1.5.3", from the header the library was built against.
std::string clblast_version();

}  // namespace mipnerf::gemm
