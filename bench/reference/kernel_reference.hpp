// The CPU reference (host/ref, double precision, one thread) of every stage that host/bench/kernel_bench times, for
// the benchmarks and tests that want it beside the device: the library and mipnerf-cl do not link the reference.
#pragma once

#include <string>
#include <vector>

#include "bench/kernel_bench.hpp"

namespace mipnerf::bench {

// The reference's version of each kernel the benchmark times, by the stage list's kernel id.
ReferenceStages reference_stages();

}  // namespace mipnerf::bench
