// The device the tests run on, checked against the platform the test stage asked for.
#include "support/test_context.hpp"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <iostream>
#include <memory>

#include "core/error.hpp"

namespace mipnerf::test {
namespace {

std::unique_ptr<ocl::Context>& context_slot() {
  static std::unique_ptr<ocl::Context> ctx;
  return ctx;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

std::string env_or_empty(const char* name) {
  const char* value = std::getenv(name);
  return value ? value : "";
}

ocl::DeviceInfo choose_test_device() {
  const auto devices = ocl::list_devices();
  const std::string selector = env_or_empty("MIPNERF_TEST_DEVICE");
  if (!selector.empty()) {
    try {
      return ocl::choose_device(devices, selector);
    } catch (const Error& e) {
      throw Error(std::string("MIPNERF_TEST_DEVICE: ") + e.what());
    }
  }
  for (const auto& d : devices) {
    if (d.type & CL_DEVICE_TYPE_CPU) return d;
  }
  throw Error("the tests need an OpenCL CPU device (PoCL: 'pocl-opencl-icd') or MIPNERF_TEST_DEVICE naming one; "
              "found: " + ocl::describe_devices(devices));
}

std::unique_ptr<ocl::Context> make_test_context() {
  const ocl::DeviceInfo device = choose_test_device();
  // Said once per test process, so every test's output shows where it ran.
  std::cerr << "tests: platform '" << device.platform_name << "', device [" << device.index << "] '" << device.name
            << "', driver " << device.driver_version << "\n";
  check_test_platform(device);
  return std::make_unique<ocl::Context>(device);
}

}  // namespace

void check_test_platform(const ocl::DeviceInfo& device) {
  const std::string wanted = env_or_empty("MIPNERF_TEST_PLATFORM");
  if (wanted.empty() || lower(wanted) == lower(device.platform_name)) return;
  throw Error("the tests run on platform '" + device.platform_name + "' (device '" + device.name +
              "'), but this test stage asked for platform '" + wanted + "' (MIPNERF_TEST_PLATFORM); MIPNERF_TEST_DEVICE='" +
              env_or_empty("MIPNERF_TEST_DEVICE") + "' chose the wrong device: qualify it with platform=NAME");
}

ocl::Context& test_context() {
  auto& ctx = context_slot();
  if (!ctx) ctx = make_test_context();
  return *ctx;
}

void release_test_context() { context_slot().reset(); }

}  // namespace mipnerf::test

namespace mipnerf::test {

// The sanitizer build (clang's __has_feature; GCC's __SANITIZE_ADDRESS__): its minutes on large batches went into
// the double reference's loops, whose memory accesses a tenth of the rays reach the same way.
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kUnderAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kUnderAddressSanitizer = true;
#else
constexpr bool kUnderAddressSanitizer = false;
#endif
#else
constexpr bool kUnderAddressSanitizer = false;
#endif

size_t batch_for_device(size_t count, size_t minimum) {
  const bool simulator = test_context().device_info().platform_name.find("Oclgrind") != std::string::npos;
  return simulator || kUnderAddressSanitizer ? std::max(std::min(count, minimum), count / 10) : count;
}

}  // namespace mipnerf::test
