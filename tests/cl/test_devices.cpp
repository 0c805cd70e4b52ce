// Device enumeration and the --device choice rule.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#ifdef __linux__
#include <sched.h>
#include <unistd.h>
#endif

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

#ifdef __linux__
TEST_CASE("devices: PoCL's workers are pinned by default, unless POCL_AFFINITY was set or the CPUs are restricted") {
  // The environment this process started with (/proc/self/environ: setenv does not change it).
  std::ifstream environ_file("/proc/self/environ", std::ios::binary);
  const std::string initial((std::istreambuf_iterator<char>(environ_file)), std::istreambuf_iterator<char>());
  std::string given;
  bool was_set = false;
  for (size_t at = 0; at < initial.size();) {
    const size_t end = std::min(initial.find('\0', at), initial.size());
    const std::string entry = initial.substr(at, end - at);
    if (entry.rfind("POCL_AFFINITY=", 0) == 0) {
      was_set = true;
      given = entry.substr(14);
    }
    at = end + 1;
  }
  cpu_set_t allowed;
  REQUIRE(sched_getaffinity(0, sizeof(allowed), &allowed) == 0);
  bool every_cpu = true;
  for (long cpu = 0; cpu < sysconf(_SC_NPROCESSORS_CONF); ++cpu) every_cpu = every_cpu && CPU_ISSET(cpu, &allowed);
  ocl::list_devices();
  const char* now = std::getenv("POCL_AFFINITY");
  INFO("POCL_AFFINITY at start: " << (was_set ? given : "unset") << ", every CPU allowed: " << every_cpu);
  if (was_set) {
    REQUIRE(now != nullptr);
    CHECK(std::string(now) == given);
  } else if (every_cpu) {
    REQUIRE(now != nullptr);
    CHECK(std::string(now) == "1");
  } else {
    CHECK(now == nullptr);
  }
}
#endif

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
  // A part of a name picks the first device whose name contains it when every such device is on one platform, and
  // is refused otherwise.
  const std::string part = upper(last.name.substr(0, std::min<size_t>(6, last.name.size())));
  std::vector<const ocl::DeviceInfo*> holders;
  for (const auto& d : devices) {
    const bool holds = upper(d.name).find(part) != std::string::npos ||
                       upper(d.platform_name).find(part) != std::string::npos ||
                       upper(d.platform_vendor).find(part) != std::string::npos;
    if (holds) holders.push_back(&d);
  }
  REQUIRE(!holders.empty());
  const bool one_platform = std::all_of(holders.begin(), holders.end(), [&](const ocl::DeviceInfo* d) {
    return d->platform_name == holders.front()->platform_name;
  });
  CAPTURE(part);
  if (one_platform) {
    CHECK(ocl::choose_device(devices, part).index == holders.front()->index);
  } else {
    CHECK_THROWS_WITH_AS(ocl::choose_device(devices, part), doctest::Contains("is ambiguous"), Error);
  }
  // Every device's exact selector picks it.
  for (const auto& d : devices) CHECK(ocl::choose_device(devices, ocl::exact_selector(d)).index == d.index);
}

namespace {

ocl::DeviceInfo mock_device(int index, int index_in_platform, const std::string& name, const std::string& platform,
                            const std::string& platform_vendor) {
  ocl::DeviceInfo d;
  d.index = index;
  d.index_in_platform = index_in_platform;
  d.name = name;
  d.platform_name = platform;
  d.platform_vendor = platform_vendor;
  d.type = CL_DEVICE_TYPE_CPU;
  return d;
}

// The message choose_device throws for `selector`, or "" when it chose.
std::string refusal(const std::vector<ocl::DeviceInfo>& devices, const std::string& selector) {
  try {
    ocl::choose_device(devices, selector);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("devices: a whole name wins over the same text inside an earlier device's name") {
  const std::vector<ocl::DeviceInfo> devices{
      mock_device(0, 0, "pthread-haswell-AMD EPYC", "Portable Computing Language", "The pocl project"),
      mock_device(1, 0, "AMD EPYC", "Intel(R) OpenCL", "Intel(R) Corporation")};
  CHECK(ocl::choose_device(devices, "amd epyc").index == 1);
  CHECK(ocl::choose_device(devices, "intel").index == 1);  // the platform's name
  CHECK(ocl::choose_device(devices, "haswell").index == 0);
  CHECK(ocl::choose_device(devices, "pocl").index == 0);  // the platform's vendor
  // A part of names on both platforms is refused, not resolved by the order the ICD loader happened to list them.
  CHECK(refusal(devices, "EPYC")
            .find("is ambiguous: it is part of names on several platforms "
                  "('Portable Computing Language', 'Intel(R) OpenCL')") != std::string::npos);
}

// On an Intel host PoCL names its CPU device after the processor, so "Intel" is part of both implementations' names
// and the first match depends on the ICD loader's platform order, which it does not fix: a stage that asked for
// Intel's runtime could run on PoCL. Here with PoCL listed first, then last.
TEST_CASE("devices: PoCL's device named after an Intel processor never stands in for Intel's runtime") {
  const auto pocl = mock_device(0, 0, "pthread-skylake-avx512-Intel(R) Xeon(R) Processor",
                                "Portable Computing Language", "The pocl project");
  const auto intel = mock_device(1, 0, "Intel(R) Xeon(R) Processor", "Intel(R) OpenCL", "Intel(R) Corporation");
  for (bool pocl_first : {true, false}) {
    CAPTURE(pocl_first);
    auto first = pocl_first ? pocl : intel, second = pocl_first ? intel : pocl;
    first.index = 0;
    second.index = 1;
    const std::vector<ocl::DeviceInfo> devices{first, second};
    const int intel_index = pocl_first ? 1 : 0, pocl_index = 1 - intel_index;
    CHECK(ocl::choose_device(devices, "platform=Intel(R) OpenCL").index == intel_index);
    CHECK(ocl::choose_device(devices, "platform=intel(r) opencl:0").index == intel_index);
    CHECK(ocl::choose_device(devices, "platform=Intel").index == intel_index);  // part of one platform's name only
    CHECK(ocl::choose_device(devices, "platform=Portable Computing Language").index == pocl_index);
    CHECK(ocl::choose_device(devices, "platform=The pocl project").index == pocl_index);  // the vendor
    CHECK(ocl::choose_device(devices, ocl::exact_selector(devices[0])).index == 0);
    CHECK(ocl::choose_device(devices, ocl::exact_selector(devices[1])).index == 1);
    CHECK(refusal(devices, "Intel").find("is ambiguous") != std::string::npos);
    CHECK(refusal(devices, "Xeon").find("is ambiguous") != std::string::npos);
    CHECK(refusal(devices, "platform=Intel(R) OpenCL:1")
              .find("asks for device 1 of platform 'Intel(R) OpenCL', "
                    "which has 1") != std::string::npos);
    CHECK(refusal(devices, "platform=o").find("is part of several platforms' names") != std::string::npos);
    CHECK(refusal(devices, "platform=nosuch").find("matches no platform") != std::string::npos);
    CHECK(refusal(devices, "platform=").find("names no platform") != std::string::npos);
  }
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
