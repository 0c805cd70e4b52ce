// The host step of `tune` (see tune_host_libraries.hpp).
#include "tune_host_libraries.hpp"

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <optional>

#include "core/error.hpp"
#include "gemm/clblast_check.hpp"
#include "gemm/cpu_sgemm_timing.hpp"
#include "gemm/gemm_backend.hpp"
#include "gemm/gemm_tuning.hpp"
#include "io/json.hpp"
#include "mlp/host_mlp.hpp"
#include "mlp/mlp_products.hpp"
#include "train/config.hpp"
#include "train/model.hpp"

namespace mipnerf::cli {
namespace {

// The products of `config` in blocks of the host MLP's rows for `samples_per_ray` (the forward's at its block rows,
// the backward's at its own), added to `shapes` by label.
void add_products(std::map<std::string, gemm::HostProductShape>& shapes, const mlp::MlpConfig& config,
                  size_t samples_per_ray) {
  const size_t target = mlp::HostMlpOptions{}.target_block_rows;
  const auto block_rows = [&](size_t target_rows) {
    return mlp::rays_per_block(target_rows, samples_per_ray) * samples_per_ray;
  };
  const size_t forward_rows = block_rows(target);
  const size_t backward_rows = block_rows(mlp::backward_block_rows_for(config.width, target));
  const auto add = [&](size_t rows, bool forward_products) {
    for (const gemm::GemmProblem& p : mlp::mlp_gemm_problems(config, rows)) {
      if ((p.kind() == gemm::GemmKind::forward) != forward_products) continue;
      const gemm::HostProductShape shape{p.shape.transpose_a, p.shape.transpose_b, p.shape.m, p.shape.n, p.shape.k};
      shapes.emplace(gemm::host_product_label(shape), shape);
    }
  };
  add(forward_rows, true);
  add(backward_rows, false);
}

std::map<std::string, gemm::HostProductShape> products_to_time(const mlp::MlpConfig& flags_network,
                                                                const std::vector<std::string>& presets) {
  std::map<std::string, gemm::HostProductShape> shapes;
  add_products(shapes, flags_network, 64);
  for (const auto& preset : presets) {
    const train::TrainConfig config = train::resolve_config(preset, "mipnerf", {});
    const graph::GraphSpec spec = train::make_graph_spec(config, false);
    add_products(shapes, spec.mlps.front(), static_cast<size_t>(config.num_samples));
  }
  return shapes;
}

gemm::GemmTuning tuning_to_update(const ocl::DeviceInfo& device, const std::string& path) {
  std::optional<gemm::GemmTuning> tuning = gemm::read_tuning(path);
  if (tuning && gemm::tuning_matches(*tuning, device)) return *tuning;
  gemm::GemmTuning fresh;  // no CLBlast parameters: CLBlast keeps its defaults
  fresh.device_name = device.name;
  fresh.driver_version = device.driver_version;
  fresh.clblast_version = gemm::clblast_version();
  return fresh;
}

}  // namespace

void tune_host_libraries(const ocl::DeviceInfo& device, const std::string& path, const mlp::MlpConfig& flags_network,
                         const std::vector<std::string>& presets, int rounds) {
  try {
    gemm::resolve_gemm_backend(gemm::GemmBackend::host, device, gemm::host_blas_available());
  } catch (const Error& e) {
    std::cerr << "mipnerf-cl: tune: no host GEMM libraries to choose between: " << e.what() << "\n";
    return;
  }
  const auto& libraries = gemm::cpu_sgemm_libraries();
  for (const auto& line : gemm::cpu_sgemm_libraries_left_out()) std::cerr << "mipnerf-cl: tune: " << line << "\n";
  gemm::HostProductTimingSettings settings;
  settings.threads = static_cast<int>(std::max<cl_uint>(1, device.compute_units));
  settings.rounds = rounds;
  const auto shapes = products_to_time(flags_network, presets);
  std::cerr << "mipnerf-cl: tune: the host MLP's products, " << shapes.size() << " shapes x " << libraries.size()
            << " libraries, " << settings.threads << " threads each on its own block (GFLOP/s, median of "
            << settings.rounds << "):\n";
  gemm::GemmTuning tuning = tuning_to_update(device, path);
  tuning.host_libraries.clear();
  io::Json measurement = io::Json::object();
  for (const auto& [label, shape] : shapes) {
    std::string best_name;
    double best = -1;
    std::fprintf(stderr, "  %-34s", label.c_str());
    for (const auto& library : libraries) {
      const gemm::HostProductTiming t = gemm::time_host_product(library, libraries.front(), shape, settings);
      if (!t.skipped.empty()) {
        measurement[label][library.name] = {{"skipped", t.skipped}};
        std::fprintf(stderr, " %s -", library.name.c_str());
        continue;
      }
      measurement[label][library.name] = {{"best", t.gflops_best}, {"median", t.gflops_median}};
      std::fprintf(stderr, " %s %.0f", library.name.c_str(), t.gflops_median);
      if (t.gflops_median > best) best = t.gflops_median, best_name = library.name;
    }
    std::fprintf(stderr, "  -> %s\n", best_name.c_str());
    tuning.host_libraries[label] = best_name;
  }
  tuning.host_libraries_measurement_json =
      io::Json{{"what", "GFLOP/s of each library on each product, the host MLP's thread arrangement"},
               {"threads", settings.threads},
               {"rounds", settings.rounds},
               {"products", measurement}}
          .dump();
  gemm::save_tuning(path, tuning);
  std::cerr << "mipnerf-cl: tune: the host MLP's library per product is in " << path << "\n";
}

}  // namespace mipnerf::cli
