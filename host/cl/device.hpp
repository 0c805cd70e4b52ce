// OpenCL platform/device enumeration and the --device choice rule.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "cl/opencl.hpp"

namespace mipnerf::ocl {

// What `mipnerf-cl devices` prints about one device, and what the library needs to size work.
struct DeviceInfo {
  int index = 0;                      // position in the flat list over all platforms
  int index_in_platform = 0;          // position among its platform's devices (the `platform=NAME:N` selector)
  std::string platform_name;          // CL_PLATFORM_NAME, e.g. "Portable Computing Language", "Intel(R) OpenCL"
  std::string platform_vendor;        // CL_PLATFORM_VENDOR, e.g. "The pocl project"
  std::string name;
  std::string vendor;
  std::string driver_version;
  std::string opencl_c_version;       // e.g. "OpenCL C 1.2 PoCL"
  cl_device_type type = 0;
  cl_uint compute_units = 0;
  cl_ulong global_mem_bytes = 0;
  cl_ulong max_alloc_bytes = 0;
  size_t max_work_group_size = 0;
  bool has_fp64 = false;
  bool host_unified_memory = false;   // CL_DEVICE_HOST_UNIFIED_MEMORY: device buffers live in host memory
  ::cl::Device device;

  std::string type_name() const;      // "GPU", "CPU", "accelerator", ...
  bool is_pocl() const;               // PoCL: barriers in partial groups and a disk kernel cache to mind
};

// Every device of every platform. Throws when the ICD loader finds no platform at all, naming the
// packages that provide one.
std::vector<DeviceInfo> list_devices();

// The --device rule (case-insensitive throughout):
//   ""                     the first GPU, else the first CPU, else the first device;
//   "N"                    the device at index N of list_devices();
//   "platform=P[:N]"       the N-th (default 0) device of ONE platform: the platform whose name or vendor is P, else
//                          the one whose name or vendor contains P; P matching parts of several platforms is an error;
//   "TEXT"                 the device whose whole name is TEXT; else the devices whose name, platform name or
//                          platform vendor contain TEXT, which must all be on one platform (the first is taken).
// Matching parts of several platforms is refused rather than resolved by list order: the ICD loader does not fix
// the order of platforms, and one implementation's device name can hold another's platform name (PoCL on an
// Intel host calls its device "pthread-skylake-avx512-Intel(R) Xeon(R) ...", which contains "Intel").
// No match → an error that lists every device. `default_rule`, when given, receives which default applied
// ("the first GPU", ...), or "" when the selector chose.
DeviceInfo choose_device(const std::vector<DeviceInfo>& devices, const std::string& selector,
                         std::string* default_rule = nullptr);

// The selector that names `device` exactly: "platform=<its platform's name>:<its index there>".
std::string exact_selector(const DeviceInfo& device);

// One line per device, as the errors and `mipnerf-cl devices` show them.
std::string describe_devices(const std::vector<DeviceInfo>& devices);

}  // namespace mipnerf::ocl
