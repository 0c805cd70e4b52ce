// The stage profile of the work one call enqueues: a test's way to ask which stages ran, their FLOPs and bytes.
#pragma once

#include "cl/context.hpp"
#include "cl/profiler.hpp"

namespace mipnerf::test {

// Runs work() as one profiled step on ctx (a context made with profiling on) and returns its profile; the profiler
// is detached again even when work throws.
template <typename Work>
ocl::StageProfile profile_once(ocl::Context& ctx, Work&& work) {
  ocl::StageProfiler profiler;
  struct Detach {
    ocl::Context& ctx;
    ~Detach() { ctx.set_profiler(nullptr); }
  } detach{ctx};
  ctx.set_profiler(&profiler);
  profiler.begin_step();
  work();
  profiler.end_step(ctx);
  return profiler.profile();
}

}  // namespace mipnerf::test
