// `mipnerf-cl devices`: every OpenCL device, and which one --device picks.
#include <cstdio>
#include <cstdlib>
#include <iostream>

#include "cl/device.hpp"
#include "common.hpp"

namespace mipnerf::cli {
namespace {

std::string gib(cl_ulong bytes) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f GiB", static_cast<double>(bytes) / (1024.0 * 1024.0 * 1024.0));
  return text;
}

// Where a selector came from: --device, or its default MIPNERF_DEVICE.
std::string selector_source(const std::string& selector) {
  const char* env = std::getenv("MIPNERF_DEVICE");
  const bool from_env = env != nullptr && selector == env;
  return (from_env ? "MIPNERF_DEVICE='" : "--device '") + selector + "'";
}

void print_device(const ocl::DeviceInfo& d, const std::string& chosen_because) {
  std::cout << "[" << d.index << "] " << d.name
            << (chosen_because.empty() ? "" : "   <- selected (" + chosen_because + ")") << "\n"
            << "    platform         " << d.platform_name << " (" << d.platform_vendor << ")\n"
            << "    select with      --device '" << ocl::exact_selector(d) << "'\n"
            << "    vendor           " << d.vendor << "\n"
            << "    type             " << d.type_name() << "\n"
            << "    compute units    " << d.compute_units << "\n"
            << "    global memory    " << gib(d.global_mem_bytes) << "\n"
            << "    max allocation   " << gib(d.max_alloc_bytes) << "\n"
            << "    max work-group   " << d.max_work_group_size << "\n"
            << "    OpenCL C         " << d.opencl_c_version << "\n"
            << "    fp64             " << (d.has_fp64 ? "yes" : "no") << "\n"
            << "    driver           " << d.driver_version << "\n";
}

void run_devices() {
  const auto devices = ocl::list_devices();
  // Resolving the selection first makes `devices --device nosuch` fail like every other command.
  const std::string& selector = global_options().device;
  std::string default_rule;
  const auto chosen = ocl::choose_device(devices, selector, &default_rule);
  const std::string reason = selector.empty() ? default_rule : selector_source(selector);
  for (const auto& d : devices) print_device(d, d.index == chosen.index ? reason : "");
}

}  // namespace

void register_devices(CLI::App& app) {
  auto* cmd = app.add_subcommand("devices", "List OpenCL devices and mark the one --device selects");
  cmd->callback(run_devices);
}

}  // namespace mipnerf::cli
