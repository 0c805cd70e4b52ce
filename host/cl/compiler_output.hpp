// What an OpenCL compiler writes to the process's stderr. PoCL compiles kernels in-process with clang, whose
// diagnostics go to the build log but whose summary ("61 warnings generated.") goes to file descriptor 2, in the
// middle of the tool's own output. Kernel builds (ours and CLBlast's) run through capture_stderr, and what it caught
// goes to the log at debug level: shown under --verbose, with the full build logs.
#pragma once

#include <functional>
#include <string>

namespace mipnerf::ocl {

// Runs `body` with file descriptor 2 sent to a scratch file and returns what was written there (trailing newlines
// stripped); the descriptor is restored before it returns or rethrows. One capture at a time in the process (a mutex):
// a nested call on the same thread runs its body inside the outer capture and returns "". Another thread's writes to
// stderr meanwhile are caught too, and reported with the compiler's.
std::string capture_stderr(const std::function<void()>& body);

}  // namespace mipnerf::ocl
