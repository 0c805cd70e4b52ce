// `mipnerf-cl tune`'s host step: which CPU GEMM library runs each of the host MLP's products on this device.
#pragma once

#include <string>
#include <vector>

#include "cl/device.hpp"
#include "mlp/mlp_config.hpp"

namespace mipnerf::cli {

// Times every CPU GEMM library built in (gemm/cpu_sgemm.hpp) on the products of `flags_network` and of the
// `presets`' networks at the host MLP's block rows, in its thread arrangement (the device's compute units as threads,
// each its own block, every library held to its thread), and stores the fastest per product, by median, in the
// tuning file at `path` (created for `device` when missing). Prints a table as it goes. Does nothing, saying why,
// where the host backend cannot run (a device with its own memory, or a build without OpenBLAS).
void tune_host_libraries(const ocl::DeviceInfo& device, const std::string& path, const mlp::MlpConfig& flags_network,
                         const std::vector<std::string>& presets, int rounds);

}  // namespace mipnerf::cli
