// Padded kernel launches.
#include "cl/launch.hpp"

#include <cstdlib>
#include <fstream>
#include <mutex>
#include <set>

namespace mipnerf::ocl {
namespace {

// With MIPNERF_KERNEL_LAUNCH_LOG=FILE, the name of each kernel function this process launches is appended to FILE
// once: the oclgrind stage collects them to prove that every kernel in kernels/ ran under the simulator
// (tests/oclgrind/oclgrind_tests.cmake). Without it (every normal run), one cached getenv per launch.
void note_launch(::cl::Kernel& kernel) {
  static const char* const log_file = std::getenv("MIPNERF_KERNEL_LAUNCH_LOG");
  if (log_file == nullptr || *log_file == '\0') return;
  static std::mutex mutex;
  static std::set<std::string> noted;
  std::string name;
  if (kernel.getInfo(CL_KERNEL_FUNCTION_NAME, &name) != CL_SUCCESS) return;
  name = name.c_str();  // some runtimes count the terminating NUL in the size
  std::lock_guard<std::mutex> lock(mutex);
  if (!noted.insert(name).second) return;
  std::ofstream(log_file, std::ios::app) << name << "\n";
}

// The caller's event, else the profiler's (when it records), else none.
::cl::Event* event_for(Context& ctx, ::cl::Event* event) { return event != nullptr ? event : profiler_event(ctx); }

}  // namespace

void launch_1d(Context& ctx, ::cl::Kernel& kernel, size_t n_items, const std::string& name, size_t local_size,
               ::cl::Event* event) {
  if (n_items == 0) return;
  note_launch(kernel);
  const size_t local = local_size ? local_size : ctx.traits().local_size_1d;
  const size_t global = round_up(n_items, local);
  check(ctx.queue().enqueueNDRangeKernel(kernel, ::cl::NullRange, ::cl::NDRange(global), ::cl::NDRange(local),
                                         nullptr, event_for(ctx, event)),
        "clEnqueueNDRangeKernel(" + name + ", " + std::to_string(n_items) + " items)");
}

void launch_2d(Context& ctx, ::cl::Kernel& kernel, size_t n_x, size_t n_y, size_t local_x, size_t local_y,
               const std::string& name, ::cl::Event* event) {
  if (n_x == 0 || n_y == 0) return;
  note_launch(kernel);
  check(ctx.queue().enqueueNDRangeKernel(kernel, ::cl::NullRange,
                                         ::cl::NDRange(round_up(n_x, local_x), round_up(n_y, local_y)),
                                         ::cl::NDRange(local_x, local_y), nullptr, event_for(ctx, event)),
        "clEnqueueNDRangeKernel(" + name + ", " + std::to_string(n_x) + "x" + std::to_string(n_y) + " items)");
}

}  // namespace mipnerf::ocl
