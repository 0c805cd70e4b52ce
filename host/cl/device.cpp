// OpenCL platform/device enumeration and the --device choice rule.
#include "cl/device.hpp"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <mutex>
#include <sstream>
#ifdef __linux__
#include <sched.h>
#include <unistd.h>
#endif

#include "cl/error.hpp"

namespace mipnerf::ocl {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// Device-info strings come back with a trailing NUL on some drivers; trim it and spaces.
std::string clean(std::string s) {
  while (!s.empty() && (s.back() == '\0' || std::isspace(static_cast<unsigned char>(s.back())))) s.pop_back();
  return s;
}

template <cl_int Name, typename T>
T query(const ::cl::Device& device, const char* what) {
  cl_int status = CL_SUCCESS;
  T value = device.getInfo<Name>(&status);
  check(status, std::string("clGetDeviceInfo(") + what + ")");
  return value;
}

DeviceInfo describe(const ::cl::Platform& platform, const ::cl::Device& device, int index) {
  DeviceInfo info;
  info.index = index;
  info.device = device;
  cl_int status = CL_SUCCESS;
  info.platform_name = clean(platform.getInfo<CL_PLATFORM_NAME>(&status));
  check(status, "clGetPlatformInfo(CL_PLATFORM_NAME)");
  info.platform_vendor = clean(platform.getInfo<CL_PLATFORM_VENDOR>(&status));
  check(status, "clGetPlatformInfo(CL_PLATFORM_VENDOR)");
  info.name = clean(query<CL_DEVICE_NAME, std::string>(device, "CL_DEVICE_NAME"));
  info.vendor = clean(query<CL_DEVICE_VENDOR, std::string>(device, "CL_DEVICE_VENDOR"));
  info.driver_version = clean(query<CL_DRIVER_VERSION, std::string>(device, "CL_DRIVER_VERSION"));
  info.opencl_c_version = clean(query<CL_DEVICE_OPENCL_C_VERSION, std::string>(device, "CL_DEVICE_OPENCL_C_VERSION"));
  info.type = query<CL_DEVICE_TYPE, cl_device_type>(device, "CL_DEVICE_TYPE");
  info.compute_units = query<CL_DEVICE_MAX_COMPUTE_UNITS, cl_uint>(device, "CL_DEVICE_MAX_COMPUTE_UNITS");
  info.global_mem_bytes = query<CL_DEVICE_GLOBAL_MEM_SIZE, cl_ulong>(device, "CL_DEVICE_GLOBAL_MEM_SIZE");
  info.max_alloc_bytes = query<CL_DEVICE_MAX_MEM_ALLOC_SIZE, cl_ulong>(device, "CL_DEVICE_MAX_MEM_ALLOC_SIZE");
  info.max_work_group_size = query<CL_DEVICE_MAX_WORK_GROUP_SIZE, size_t>(device, "CL_DEVICE_MAX_WORK_GROUP_SIZE");
  // fp64 is reported either as a non-zero double config (1.2+) or through the cl_khr_fp64 extension.
  cl_device_fp_config fp64 = 0;
  status = clGetDeviceInfo(device(), CL_DEVICE_DOUBLE_FP_CONFIG, sizeof(fp64), &fp64, nullptr);
  const std::string extensions = query<CL_DEVICE_EXTENSIONS, std::string>(device, "CL_DEVICE_EXTENSIONS");
  info.has_fp64 = (status == CL_SUCCESS && fp64 != 0) || extensions.find("cl_khr_fp64") != std::string::npos;
  // Deprecated in OpenCL 2.0 but still answered by every ICD we know (PoCL: true on its CPU device); a device
  // that does not answer is taken to have its own memory, so nothing relies on sharing it.
  cl_bool unified = CL_FALSE;
  status = clGetDeviceInfo(device(), CL_DEVICE_HOST_UNIFIED_MEMORY, sizeof(unified), &unified, nullptr);
  info.host_unified_memory = status == CL_SUCCESS && unified == CL_TRUE;
  return info;
}

}  // namespace

std::string DeviceInfo::type_name() const {
  if (type & CL_DEVICE_TYPE_GPU) return "GPU";
  if (type & CL_DEVICE_TYPE_CPU) return "CPU";
  if (type & CL_DEVICE_TYPE_ACCELERATOR) return "accelerator";
  return "other";
}

bool DeviceInfo::is_pocl() const {
  return lower(platform_name).find("portable computing language") != std::string::npos ||
         lower(driver_version).find("pocl") != std::string::npos ||
         lower(opencl_c_version).find("pocl") != std::string::npos;
}

// PoCL's CPU device runs a kernel on worker threads that Linux places as it likes; waking the second one for a short
// launch, the scheduler often puts it on the CPU of the first (which is busy), so the launch runs on one thread:
// on the 2-core machine of bench/results/kernel_runtimes/kernel_runtimes_xeon.md the sampler, render_fwd and the activations measured
// either their two-thread or their one-thread time from run to run. PoCL pins worker i to CPU i when POCL_AFFINITY=1
// (PoCL ≥ 1.6), which the tiny preset's training measured +30 % rays/s with (render −15 % s/MP; quick unchanged). So
// it is the default here, set before PoCL reads it (at its first platform query), unless the user set
// POCL_AFFINITY, and only where this process may run on every CPU: PoCL aborts if it cannot pin (a CPU outside a
// restricted affinity mask, e.g. under taskset or a container's cpuset).
void pin_pocl_workers_by_default() {
#ifdef __linux__
  if (std::getenv("POCL_AFFINITY")) return;
  const long configured = sysconf(_SC_NPROCESSORS_CONF);
  cpu_set_t allowed;
  if (configured < 1 || configured > CPU_SETSIZE || sched_getaffinity(0, sizeof(allowed), &allowed) != 0) return;
  for (long cpu = 0; cpu < configured; ++cpu) {
    if (!CPU_ISSET(static_cast<int>(cpu), &allowed)) return;
  }
  setenv("POCL_AFFINITY", "1", 0);
#endif
}

std::vector<DeviceInfo> list_devices() {
  static std::once_flag pocl_environment;
  std::call_once(pocl_environment, pin_pocl_workers_by_default);
  std::vector<::cl::Platform> platforms;
  const cl_int status = ::cl::Platform::get(&platforms);
  if (status == -1001 /* CL_PLATFORM_NOT_FOUND_KHR */ || (status == CL_SUCCESS && platforms.empty())) {
    throw Error(
        "no OpenCL platform found: install the ICD loader 'ocl-icd-libopencl1' and a driver, e.g. PoCL for "
        "CPUs ('pocl-opencl-icd'), or run scripts/install-deps.sh",
        {}, -1001);
  }
  check(status, "clGetPlatformIDs");
  std::vector<DeviceInfo> devices;
  for (const auto& platform : platforms) {
    std::vector<::cl::Device> platform_devices;
    const cl_int device_status = platform.getDevices(CL_DEVICE_TYPE_ALL, &platform_devices);
    if (device_status == CL_DEVICE_NOT_FOUND) continue;  // a platform with no device is not an error
    check(device_status, "clGetDeviceIDs");
    int index_in_platform = 0;
    for (const auto& device : platform_devices) {
      devices.push_back(describe(platform, device, static_cast<int>(devices.size())));
      devices.back().index_in_platform = index_in_platform++;
    }
  }
  if (devices.empty()) {
    throw Error("OpenCL platforms exist but none has a device: install a driver, e.g. 'pocl-opencl-icd' for CPUs");
  }
  return devices;
}

namespace {

bool contains(const std::string& haystack, const std::string& lower_needle) {
  return lower(haystack).find(lower_needle) != std::string::npos;
}

bool all_digits(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
}

// The distinct platform names among `matches`, quoted, for an ambiguity error.
std::string platforms_of(const std::vector<const DeviceInfo*>& matches) {
  std::vector<std::string> names;
  for (const auto* d : matches) {
    if (std::find(names.begin(), names.end(), d->platform_name) == names.end()) names.push_back(d->platform_name);
  }
  std::string out;
  for (const auto& name : names) out += (out.empty() ? "'" : ", '") + name + "'";
  return out;
}

size_t platform_count(const std::vector<const DeviceInfo*>& matches) {
  std::vector<std::string> names;
  for (const auto* d : matches) {
    if (std::find(names.begin(), names.end(), d->platform_name) == names.end()) names.push_back(d->platform_name);
  }
  return names.size();
}

[[noreturn]] void no_match(const std::vector<DeviceInfo>& devices, const std::string& selector,
                           const std::string& why) {
  throw Error("--device '" + selector + "' " + why + "; the devices are: " + describe_devices(devices) +
              " (give an index, part of a name, or platform=NAME[:N])");
}

// "platform=P[:N]": one platform by its whole name or vendor, else by part of them, then its N-th device.
const DeviceInfo& choose_by_platform(const std::vector<DeviceInfo>& devices, const std::string& selector) {
  std::string platform = selector.substr(std::string("platform=").size());
  int index = 0;
  const auto colon = platform.rfind(':');
  if (colon != std::string::npos && all_digits(platform.substr(colon + 1)) && platform.size() - colon <= 9) {
    index = std::stoi(platform.substr(colon + 1));
    platform = platform.substr(0, colon);
  }
  if (platform.empty()) no_match(devices, selector, "names no platform");
  const std::string needle = lower(platform);
  std::vector<const DeviceInfo*> matches;
  for (const auto& d : devices) {
    if (lower(d.platform_name) == needle || lower(d.platform_vendor) == needle) matches.push_back(&d);
  }
  if (matches.empty()) {
    for (const auto& d : devices) {
      if (contains(d.platform_name, needle) || contains(d.platform_vendor, needle)) matches.push_back(&d);
    }
  }
  if (matches.empty()) no_match(devices, selector, "matches no platform");
  if (platform_count(matches) > 1) {
    no_match(devices, selector,
             "is part of several platforms' names (" + platforms_of(matches) + "): give more of the one you mean");
  }
  for (const auto* d : matches) {
    if (d->index_in_platform == index) return *d;
  }
  no_match(devices, selector,
           "asks for device " + std::to_string(index) + " of platform '" + matches.front()->platform_name +
               "', which has " + std::to_string(matches.size()));
}

}  // namespace

DeviceInfo choose_device(const std::vector<DeviceInfo>& devices, const std::string& selector,
                         std::string* default_rule) {
  if (devices.empty()) throw Error("no OpenCL device to choose from");
  std::string unused;
  std::string& rule = default_rule ? *default_rule : unused;
  rule.clear();
  if (selector.empty()) {
    for (cl_device_type wanted : {cl_device_type(CL_DEVICE_TYPE_GPU), cl_device_type(CL_DEVICE_TYPE_CPU)}) {
      for (const auto& d : devices) {
        if (d.type & wanted) {
          rule = wanted == CL_DEVICE_TYPE_GPU ? "the first GPU" : "the first CPU device; no GPU";
          return d;
        }
      }
    }
    rule = "the first device; no GPU or CPU device";
    return devices.front();
  }
  if (all_digits(selector)) {
    // More than 9 digits is no index of any list (and would overflow stoul).
    if (selector.size() <= 9 && std::stoul(selector) < devices.size()) return devices[std::stoul(selector)];
    no_match(devices, selector, "matches no OpenCL device");
  }
  if (lower(selector).rfind("platform=", 0) == 0) return choose_by_platform(devices, selector);
  // A device's whole name wins over parts of others' (Intel's CPU runtime calls its device "AMD EPYC", which is
  // also part of PoCL's "pthread-haswell-AMD EPYC").
  const std::string needle = lower(selector);
  for (const auto& d : devices) {
    if (lower(d.name) == needle) return d;
  }
  std::vector<const DeviceInfo*> matches;
  for (const auto& d : devices) {
    if (contains(d.name, needle) || contains(d.platform_name, needle) || contains(d.platform_vendor, needle)) {
      matches.push_back(&d);
    }
  }
  if (matches.empty()) no_match(devices, selector, "matches no OpenCL device");
  if (platform_count(matches) > 1) {
    no_match(devices, selector,
             "is ambiguous: it is part of names on several platforms (" + platforms_of(matches) +
                 "): choose one with platform=NAME[:N] or an index");
  }
  return *matches.front();
}

std::string exact_selector(const DeviceInfo& device) {
  return "platform=" + device.platform_name + ":" + std::to_string(device.index_in_platform);
}

std::string describe_devices(const std::vector<DeviceInfo>& devices) {
  std::ostringstream out;
  for (size_t i = 0; i < devices.size(); ++i) {
    const auto& d = devices[i];
    if (i) out << "; ";
    out << "[" << d.index << "] " << d.name << " (" << d.type_name() << ", " << d.platform_name << ")";
  }
  return out.str();
}

}  // namespace mipnerf::ocl
