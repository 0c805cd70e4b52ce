// The CPU reference (host/ref, double precision, one thread) of every stage that host/bench/kernel_bench times, for
// the benchmarks and tests that want it beside the device: the library and mipnerf-cl do not link the reference.
#pragma once

#include "bench/kernel_bench.hpp"

namespace mipnerf::bench {

// The reference's version of each kernel-bench stage, looked up by the stage's name.
ReferenceStages reference_stages();

}  // namespace mipnerf::bench
