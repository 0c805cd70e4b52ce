// The device the tests run on.
#include "support/test_context.hpp"

#include <cstdlib>
#include <memory>

#include "core/error.hpp"

namespace mipnerf::test {

ocl::Context& test_context() {
  static std::unique_ptr<ocl::Context> ctx = [] {
    const auto devices = ocl::list_devices();
    const char* selector = std::getenv("MIPNERF_TEST_DEVICE");
    if (selector && *selector) return std::make_unique<ocl::Context>(ocl::choose_device(devices, selector));
    for (const auto& d : devices) {
      if (d.type & CL_DEVICE_TYPE_CPU) return std::make_unique<ocl::Context>(d);
    }
    throw Error("the tests need an OpenCL CPU device (PoCL: 'pocl-opencl-icd'); found: " +
                ocl::describe_devices(devices));
  }();
  return *ctx;
}

}  // namespace mipnerf::test
