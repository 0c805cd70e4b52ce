// What `mipnerf-cl tune` measures about whole backends, below the CLI: which backend gemm_backend=auto takes on a
// device (the whole network timed on each of gemm::gemm_backends()), and which of the host MLP's products the host step
// chooses a CPU GEMM library for (the networks of the flags and of the presets).
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "cl/device.hpp"
#include "gemm/cpu_sgemm.hpp"
#include "gemm/gemm_backend.hpp"
#include "mlp/mlp_config.hpp"

namespace mipnerf::bench {

// What the measurement found: the faster backend and every backend's seconds (forward + backward of one chunk).
struct AutoBackendMeasurement {
  gemm::GemmBackend fastest = gemm::GemmBackend::clblast;
  size_t rows = 0;                                            // samples per chunk timed
  std::vector<std::pair<gemm::GemmBackend, double>> seconds;  // gemm_backends() order, those that run on the device
};

// Times training forward + backward of `config` on one chunk of about `rows` rows (64 samples a ray), best of 2 after a
// warm-up, on each backend of gemm::gemm_backends() that runs on `device` in this build, CLBlast with the tuning file
// at `path`; the fastest becomes the file's auto_backend (with the measurement). Per network rather than per product:
// the host path fuses the products with their element-wise work (mlp/host_mlp.hpp), so a product alone is not what
// it runs. Nothing (and the file unchanged) when `path` does not exist or no backend runs.
std::optional<AutoBackendMeasurement> measure_auto_backend(const ocl::DeviceInfo& device, const std::string& path,
                                                           const mlp::MlpConfig& config, size_t rows);

// The host MLP's products (label → shape, mlp::host_mlp_products at its default blocks) of `network` at 64 samples a
// ray and of each preset's network at its samples per level: what tune's host step times.
std::map<std::string, gemm::HostProductShape> host_products_to_tune(const mlp::MlpConfig& network,
                                                                    const std::vector<std::string>& presets);

}  // namespace mipnerf::bench
