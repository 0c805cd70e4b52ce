// OpenCL status names and check(): a failed OpenCL call becomes a mipnerf::Error naming the call and the status.
#pragma once

#include <string>

#include "cl/opencl.hpp"
#include "core/error.hpp"

namespace mipnerf::ocl {

// "CL_OUT_OF_RESOURCES" for -5; "unknown OpenCL status -1234" for codes outside the standard.
std::string status_name(cl_int status);

// Throws mipnerf::Error naming the call (e.g. "clEnqueueNDRangeKernel(render_fwd)") and the status by name.
void check(cl_int status, const std::string& call);

}  // namespace mipnerf::ocl
