// The device the tests run on: PoCL's CPU device unless MIPNERF_TEST_DEVICE selects another.
#pragma once

#include "cl/context.hpp"

namespace mipnerf::test {

// One context per test process, created on first use. MIPNERF_TEST_DEVICE takes the same
// selector as --device; by default the first CPU device (PoCL's) is used.
ocl::Context& test_context();

}  // namespace mipnerf::test
