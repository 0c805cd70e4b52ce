// `mipnerf-cl tune`'s host step, below the CLI: which CPU GEMM library (cpu_sgemm.hpp) runs each of the host MLP's
// products on a device. Times every library built in on each product in the host MLP's thread arrangement, chooses
// the fastest by median, and stores the choice with its measurement in the device's tuning file (gemm_tuning.hpp),
// keeping the file's CLBlast parameters when the file is for this device.
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "cl/device.hpp"
#include "gemm/cpu_sgemm.hpp"
#include "gemm/cpu_sgemm_timing.hpp"

namespace mipnerf::gemm {

// The host MLP's thread arrangement on `device` (its compute units as threads, each its own block, every library
// held to its thread), `rounds` timed batches per product and library.
HostProductTimingSettings host_library_timing_settings(const ocl::DeviceInfo& device, int rounds);

// Throws mipnerf::Error saying why the host MLP's libraries cannot be chosen on `device` (a device with its own
// memory, or a build without OpenBLAS: the host backend cannot run there).
void check_host_libraries_can_run(const ocl::DeviceInfo& device);

// One product timed on every library, and the one chosen ("" when every library skipped it).
struct HostProductChoice {
  std::string label;
  std::vector<std::pair<std::string, HostProductTiming>> timings;  // library name → timing, cpu_sgemm_libraries order
  std::string chosen;
};

// Times every library on each of `products` (label → shape) under `settings`, calling `on_product` after each, and
// writes the choices with their measurement to the tuning file at `path` (created for `device` when missing or made
// for another device). Returns the choices, label → library. Throws what check_host_libraries_can_run throws.
std::map<std::string, std::string> tune_host_libraries(const ocl::DeviceInfo& device, const std::string& path,
                                                       const std::map<std::string, HostProductShape>& products,
                                                       const HostProductTimingSettings& settings,
                                                       const std::function<void(const HostProductChoice&)>& on_product);

}  // namespace mipnerf::gemm
