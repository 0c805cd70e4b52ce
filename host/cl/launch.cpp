// Padded kernel launches.
#include "cl/launch.hpp"

namespace mipnerf::ocl {
namespace {

// The caller's event, else the profiler's (when it records), else none.
::cl::Event* event_for(Context& ctx, ::cl::Event* event) { return event != nullptr ? event : profiler_event(ctx); }

}  // namespace

void launch_1d(Context& ctx, ::cl::Kernel& kernel, size_t n_items, const std::string& name, size_t local_size,
               ::cl::Event* event) {
  if (n_items == 0) return;
  const size_t local = local_size ? local_size : ctx.traits().local_size_1d;
  const size_t global = round_up(n_items, local);
  check(ctx.queue().enqueueNDRangeKernel(kernel, ::cl::NullRange, ::cl::NDRange(global), ::cl::NDRange(local),
                                         nullptr, event_for(ctx, event)),
        "clEnqueueNDRangeKernel(" + name + ", " + std::to_string(n_items) + " items)");
}

void launch_2d(Context& ctx, ::cl::Kernel& kernel, size_t n_x, size_t n_y, size_t local_x, size_t local_y,
               const std::string& name, ::cl::Event* event) {
  if (n_x == 0 || n_y == 0) return;
  check(ctx.queue().enqueueNDRangeKernel(kernel, ::cl::NullRange,
                                         ::cl::NDRange(round_up(n_x, local_x), round_up(n_y, local_y)),
                                         ::cl::NDRange(local_x, local_y), nullptr, event_for(ctx, event)),
        "clEnqueueNDRangeKernel(" + name + ", " + std::to_string(n_x) + "x" + std::to_string(n_y) + " items)");
}

}  // namespace mipnerf::ocl
