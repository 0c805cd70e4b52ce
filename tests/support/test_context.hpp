// The device the tests run on: PoCL's CPU device unless MIPNERF_TEST_DEVICE selects another.
#pragma once

#include <cstddef>

#include "cl/context.hpp"

namespace mipnerf::test {

// One context per test process, created on first use. MIPNERF_TEST_DEVICE takes the same
// selector as --device; by default the first CPU device (PoCL's) is used. Prints the platform and device once (to
// stderr). Throws mipnerf::Error naming the devices found when there is no such device, and when the device is not
// on the platform MIPNERF_TEST_PLATFORM names (check_test_platform), so no test passes on the wrong runtime.
ocl::Context& test_context();

// Throws mipnerf::Error when MIPNERF_TEST_PLATFORM is set and `device`'s platform name is another (case aside): the
// test stage of scripts/test.sh asked for one implementation and the selector found another.
void check_test_platform(const ocl::DeviceInfo& device);

// `count` (rays, rows) for a test's batch on the test device: the count itself, but a tenth of it (at least
// `minimum`) on the oclgrind simulator, which runs every work-item through an interpreter, and in the
// AddressSanitizer build. What the simulator checks (out-of-bounds accesses, races, API misuse) and what the
// sanitizers check (the host's accesses in the wrappers and the reference) do not depend on how many rays share the
// code; the accuracy checks keep their full sizes on the real runtimes (PoCL, Intel's) in the plain build.
size_t batch_for_device(size_t count, size_t minimum = 64);

// Releases the context (its programs, queue and buffers) if it was made. test_main calls it after the tests, before
// the process's static destructors run: an OpenCL implementation's own statics may be gone by then (oclgrind's are:
// releasing a program during exit corrupted its heap).
void release_test_context();

}  // namespace mipnerf::test
