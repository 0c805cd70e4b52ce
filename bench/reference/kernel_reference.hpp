// The CPU reference (host/ref, double precision, one thread) of every stage that host/bench/kernel_bench times, for
// the benchmarks and tests that want it beside the device: the library and mipnerf-cl do not link the reference.
#pragma once

#include <string>
#include <vector>

#include "bench/kernel_bench.hpp"

namespace mipnerf::bench {

// The reference's version of each kernel the benchmark times, looked up by the kernel's name (e.g. "render_fwd").
ReferenceStages reference_stages();

// The kernels reference_stages() knows, sorted (for the test that it and the stage list name the same kernels).
std::vector<std::string> reference_kernels();

}  // namespace mipnerf::bench
