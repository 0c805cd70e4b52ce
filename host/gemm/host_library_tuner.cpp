// The host step of `tune` (see host_library_tuner.hpp): the search, the choice and the store update.
#include "gemm/host_library_tuner.hpp"

#include <algorithm>
#include <optional>

#include "gemm/clblast_check.hpp"
#include "gemm/gemm_backend.hpp"
#include "gemm/gemm_tuning.hpp"
#include "io/json.hpp"

namespace mipnerf::gemm {
namespace {

// The device's file as it stands (its CLBlast parameters kept), or a fresh one for `device`.
GemmTuning tuning_to_update(const ocl::DeviceInfo& device, const std::string& path) {
  std::optional<GemmTuning> tuning = read_tuning(path);
  if (tuning && tuning_matches(*tuning, device)) return *tuning;
  GemmTuning fresh;  // no CLBlast parameters: CLBlast keeps its defaults
  fresh.device_name = device.name;
  fresh.driver_version = device.driver_version;
  fresh.clblast_version = clblast_version();
  return fresh;
}

// Every library on one product; the fastest by median is chosen. `measurement` gets each library's figures.
HostProductChoice time_product(const std::string& label, const HostProductShape& shape,
                               const HostProductTimingSettings& settings, io::Json& measurement) {
  const auto& libraries = cpu_sgemm_libraries();
  HostProductChoice choice;
  choice.label = label;
  double best = -1;
  for (const auto& library : libraries) {
    const HostProductTiming t = time_host_product(library, libraries.front(), shape, settings);
    choice.timings.emplace_back(library.name, t);
    if (!t.skipped.empty()) {
      measurement[library.name] = {{"skipped", t.skipped}};
      continue;
    }
    measurement[library.name] = {{"best", t.gflops_best}, {"median", t.gflops_median}};
    if (t.gflops_median > best) best = t.gflops_median, choice.chosen = library.name;
  }
  return choice;
}

}  // namespace

HostProductTimingSettings host_library_timing_settings(const ocl::DeviceInfo& device, int rounds) {
  HostProductTimingSettings settings;
  settings.threads = static_cast<int>(std::max<cl_uint>(1, device.compute_units));
  settings.rounds = rounds;
  return settings;
}

void check_host_libraries_can_run(const ocl::DeviceInfo& device) {
  resolve_gemm_backend(GemmBackend::host, device, host_blas_available());
}

std::map<std::string, std::string> tune_host_libraries(
    const ocl::DeviceInfo& device, const std::string& path, const std::map<std::string, HostProductShape>& products,
    const HostProductTimingSettings& settings, const std::function<void(const HostProductChoice&)>& on_product) {
  check_host_libraries_can_run(device);
  GemmTuning tuning = tuning_to_update(device, path);
  tuning.host_libraries.clear();
  io::Json measurement = io::Json::object();
  for (const auto& [label, shape] : products) {
    const HostProductChoice choice = time_product(label, shape, settings, measurement[label]);
    if (on_product) on_product(choice);
    tuning.host_libraries[label] = choice.chosen;
  }
  tuning.host_libraries_measurement_json = io::Json{
      {"what", "GFLOP/s of each library on each product, the host MLP's thread arrangement"},
      {"threads", settings.threads},
      {"rounds", settings.rounds},
      {"products", measurement}}.dump();
  save_tuning(path, tuning);
  return tuning.host_libraries;
}

}  // namespace mipnerf::gemm
