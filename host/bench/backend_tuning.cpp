// tune's measurements of whole backends (see backend_tuning.hpp).
#include "bench/backend_tuning.hpp"

#include <algorithm>
#include <memory>

#include "bench/gemm_bench.hpp"
#include "core/error.hpp"
#include "gemm/gemm_tuning.hpp"
#include "io/json.hpp"
#include "mlp/mlp_products.hpp"
#include "mlp/network.hpp"
#include "train/config.hpp"
#include "train/model.hpp"

namespace mipnerf::bench {

std::optional<AutoBackendMeasurement> measure_auto_backend(const ocl::DeviceInfo& device, const std::string& path,
                                                           const mlp::MlpConfig& config, size_t rows) {
  std::optional<gemm::GemmTuning> tuning = gemm::read_tuning(path);
  if (!tuning) return std::nullopt;
  ocl::Context ctx(device);
  gemm::install_gemm_tuning(ctx, *tuning);  // the parameters just found, whatever file `path` is
  const size_t samples = 64, rays = std::max<size_t>(1, rows / samples);
  AutoBackendMeasurement measured;
  measured.rows = rays * samples;
  io::Json seconds = io::Json::object();
  double fastest_seconds = 0;
  for (const gemm::GemmBackend backend : gemm::gemm_backends()) {
    std::unique_ptr<mlp::Network> net;
    try {
      net = mlp::make_network(ctx, config, backend);
    } catch (const Error&) {
      continue;  // not possible on this device or in this build
    }
    const MlpChunkTimes t = time_mlp_chunk(ctx, *net, rays, samples, 2);
    const double step = t.forward + t.backward;
    seconds[enum_name(backend)] = step;
    if (measured.seconds.empty() || step < fastest_seconds) measured.fastest = backend, fastest_seconds = step;
    measured.seconds.emplace_back(backend, step);
  }
  if (measured.seconds.empty()) return std::nullopt;
  tuning->auto_backend = measured.fastest;
  tuning->backend_measurement_json = io::Json{
      {"what", "training forward + backward of the whole network, best of 2 after a warm-up"},
      {"network", mlp::describe(config)},
      {"rows", measured.rows},
      {"seconds", seconds}}.dump();
  gemm::save_tuning(path, *tuning);
  return measured;
}

std::map<std::string, gemm::HostProductShape> host_products_to_tune(const mlp::MlpConfig& network,
                                                                    const std::vector<std::string>& presets) {
  std::map<std::string, gemm::HostProductShape> shapes;
  const auto add = [&shapes](const mlp::MlpConfig& config, size_t samples_per_ray) {
    for (const mlp::HostMlpProduct& p : mlp::host_mlp_products(config, samples_per_ray))
      shapes.emplace(p.label, p.shape);
  };
  add(network, 64);
  for (const auto& preset : presets) {
    const train::TrainConfig config = train::resolve_config(preset, train::preset_variant(preset), {});
    add(train::make_graph_spec(config, false).mlps.front(), static_cast<size_t>(config.num_samples));
  }
  return shapes;
}

}  // namespace mipnerf::bench
