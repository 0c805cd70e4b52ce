// The one exception type of the library: a failed OpenCL/CLBlast call, a failed kernel build, or bad input.
#pragma once

#include <stdexcept>
#include <string>

#include "cl/opencl.hpp"

namespace mipnerf {

// Every failure the library reports. what() is one line a person can act on (the CLI prints it as is);
// details() holds what does not fit on a line, e.g. a kernel's full build log.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message, std::string details = {}, int status = 0)
      : std::runtime_error(message), details_(std::move(details)), status_(status) {}
  const std::string& details() const { return details_; }
  // The OpenCL or CLBlast status code, 0 for errors that did not come from a call.
  int status() const { return status_; }

 private:
  std::string details_;
  int status_;
};

namespace ocl {

// "CL_OUT_OF_RESOURCES" for -5; "unknown OpenCL status -1234" for codes outside the standard.
std::string status_name(cl_int status);

// Throws mipnerf::Error naming the call (e.g. "clEnqueueNDRangeKernel(render_fwd)") and the status by name.
void check(cl_int status, const std::string& call);

}  // namespace ocl
}  // namespace mipnerf
