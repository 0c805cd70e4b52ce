// The device the tests run on.
#include "support/test_context.hpp"

#include <cstdlib>
#include <memory>

#include "core/error.hpp"

namespace mipnerf::test {
namespace {

std::unique_ptr<ocl::Context>& context_slot() {
  static std::unique_ptr<ocl::Context> ctx;
  return ctx;
}

std::unique_ptr<ocl::Context> make_test_context() {
  const auto devices = ocl::list_devices();
  const char* selector = std::getenv("MIPNERF_TEST_DEVICE");
  if (selector && *selector) {
    try {
      return std::make_unique<ocl::Context>(ocl::choose_device(devices, selector));
    } catch (const Error& e) {
      throw Error(std::string("MIPNERF_TEST_DEVICE: ") + e.what());
    }
  }
  for (const auto& d : devices) {
    if (d.type & CL_DEVICE_TYPE_CPU) return std::make_unique<ocl::Context>(d);
  }
  throw Error("the tests need an OpenCL CPU device (PoCL: 'pocl-opencl-icd') or MIPNERF_TEST_DEVICE naming one; "
              "found: " + ocl::describe_devices(devices));
}

}  // namespace

ocl::Context& test_context() {
  auto& ctx = context_slot();
  if (!ctx) ctx = make_test_context();
  return *ctx;
}

void release_test_context() { context_slot().reset(); }

}  // namespace mipnerf::test
