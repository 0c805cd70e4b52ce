// Device enumeration and the --device choice rule.
#include <doctest/doctest.h>

#include "cl/device.hpp"
#include "cl/error.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

TEST_CASE("devices: enumeration finds a CPU device with sane properties") {
  const auto devices = ocl::list_devices();
  REQUIRE(!devices.empty());
  bool has_cpu = false;
  for (size_t i = 0; i < devices.size(); ++i) {
    const auto& d = devices[i];
    CHECK(d.index == static_cast<int>(i));
    CHECK(!d.name.empty());
    CHECK(!d.platform_name.empty());
    CHECK(d.compute_units >= 1);
    CHECK(d.global_mem_bytes >= d.max_alloc_bytes);
    CHECK(d.max_alloc_bytes > 0);
    CHECK(d.max_work_group_size >= 1);
    CHECK(d.opencl_c_version.find("OpenCL C") != std::string::npos);
    has_cpu = has_cpu || (d.type & CL_DEVICE_TYPE_CPU);
  }
  CHECK(has_cpu);
}

TEST_CASE("devices: choice by default, index and name substring") {
  const auto devices = ocl::list_devices();
  const auto by_default = ocl::choose_device(devices, "");
  bool any_gpu = false;
  for (const auto& d : devices) any_gpu = any_gpu || (d.type & CL_DEVICE_TYPE_GPU);
  CHECK((by_default.type & (any_gpu ? CL_DEVICE_TYPE_GPU : CL_DEVICE_TYPE_CPU)) != 0);

  const auto last = devices.back();
  CHECK(ocl::choose_device(devices, std::to_string(last.index)).index == last.index);
  auto upper = [](std::string s) {
    for (auto& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    return s;
  };
  // A device's whole name, in any case, picks it, even where it is part of an earlier device's name (Intel's CPU
  // runtime names its device "AMD EPYC", part of PoCL's "pthread-haswell-AMD EPYC").
  for (const auto& d : devices) {
    CAPTURE(d.name);
    CHECK(ocl::choose_device(devices, upper(d.name)).name == d.name);
  }
  // A part of a name picks the first device whose name contains it.
  const std::string part = upper(last.name.substr(0, std::min<size_t>(6, last.name.size())));
  for (const auto& d : devices) {
    if (upper(d.name).find(part) == std::string::npos) continue;
    CHECK(ocl::choose_device(devices, part).index == d.index);
    break;
  }
}

TEST_CASE("devices: a whole name wins over the same text inside an earlier device's name") {
  ocl::DeviceInfo pocl, intel;
  pocl.index = 0;
  pocl.name = "pthread-haswell-AMD EPYC";
  pocl.platform_name = "Portable Computing Language";
  intel.index = 1;
  intel.name = "AMD EPYC";
  intel.platform_name = "Intel(R) OpenCL";
  const std::vector<ocl::DeviceInfo> devices{pocl, intel};
  CHECK(ocl::choose_device(devices, "amd epyc").index == 1);
  CHECK(ocl::choose_device(devices, "EPYC").index == 0);   // a part: the first that contains it
  CHECK(ocl::choose_device(devices, "intel").index == 1);  // the platform's name
  CHECK(ocl::choose_device(devices, "haswell").index == 0);
}

TEST_CASE("devices: the default choice says which rule applied") {
  ocl::DeviceInfo cpu, gpu, other;
  cpu.index = 0;
  cpu.type = CL_DEVICE_TYPE_CPU;
  gpu.index = 1;
  gpu.type = CL_DEVICE_TYPE_GPU;
  other.index = 0;
  other.type = CL_DEVICE_TYPE_ACCELERATOR;
  std::string rule = "stale";
  CHECK(ocl::choose_device({cpu, gpu}, "", &rule).index == 1);
  CHECK(rule == "the first GPU");
  CHECK(ocl::choose_device({cpu}, "", &rule).index == 0);
  CHECK(rule == "the first CPU device; no GPU");
  CHECK(ocl::choose_device({other}, "", &rule).index == 0);
  CHECK(rule == "the first device; no GPU or CPU device");
  CHECK(ocl::choose_device({cpu, gpu}, "0", &rule).index == 0);
  CHECK(rule.empty());  // the selector chose
}

TEST_CASE("devices: no match lists every device") {
  const auto devices = ocl::list_devices();
  for (const std::string selector : {"nosuch-device", "999"}) {
    try {
      ocl::choose_device(devices, selector);
      FAIL("expected an error for --device " << selector);
    } catch (const Error& e) {
      const std::string message = e.what();
      CHECK(message.find("'" + selector + "'") != std::string::npos);
      for (const auto& d : devices) CHECK(message.find(d.name) != std::string::npos);
      CHECK(message.find('\n') == std::string::npos);
    }
  }
}

TEST_CASE("devices: the test context runs on PoCL's CPU device") {
  auto& ctx = test::test_context();
  CHECK((ctx.device_info().type & CL_DEVICE_TYPE_CPU) != 0);
  CHECK(ctx.traits().local_size_1d >= 1);
}

TEST_CASE("errors: OpenCL statuses are named") {
  CHECK(ocl::status_name(CL_OUT_OF_RESOURCES) == "CL_OUT_OF_RESOURCES");
  CHECK(ocl::status_name(CL_BUILD_PROGRAM_FAILURE) == "CL_BUILD_PROGRAM_FAILURE");
  CHECK(ocl::status_name(-12345).find("-12345") != std::string::npos);
  try {
    ocl::check(CL_INVALID_KERNEL_ARGS, "clEnqueueNDRangeKernel(render_fwd)");
    FAIL("check() must throw on a failed status");
  } catch (const Error& e) {
    CHECK(std::string(e.what()) == "clEnqueueNDRangeKernel(render_fwd) failed with CL_INVALID_KERNEL_ARGS");
    CHECK(e.status() == CL_INVALID_KERNEL_ARGS);
  }
  CHECK_NOTHROW(ocl::check(CL_SUCCESS, "anything"));
}
