// Per-device CLBlast GEMM parameters: product shapes, the store `mipnerf-cl tune` writes (one JSON file
// per device name, driver version and CLBlast version under the user's cache folder), and how a run installs
// it through clblast::OverrideParameters before its first GEMM.
//
// CLBlast's GEMM routine uses these kernels, each with its own parameter set (all names must be given to
// OverrideParameters; see RetrieveParameters): "Xgemm" (the indirect kernel: GEMMK, KREG, KWG, KWI, MDIMA,
// MDIMC, MWG, NDIMB, NDIMC, NWG, SA, SB, STRM, STRN, VWM, VWN), "XgemmDirect" (KWID, MDIMAD, MDIMCD, NDIMBD,
// NDIMCD, PADA, PADB, VWMD, VWND, WGD), its helpers "Copy" (COPY_*), "Pad" (PAD_*), "Transpose" (TRA_*),
// "Padtranspose" (PADTRA_*), and "GemmRoutine" (XGEMM_MIN_INDIRECT_SIZE: products with m·n·k below its cube
// run the direct kernel). Which helpers run depends on the layout: for row-major C = A·B, Xgemm with GEMMK = 0
// needs A and C transposed (two extra passes over the big matrices), GEMMK = 1 needs neither; for the weight
// gradient Aᵀ·B it is the other way round. That is why parameters can be chosen per product kind.
#pragma once

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "cl/context.hpp"
#include "gemm/gemm.hpp"
#include "gemm/cpu_sgemm.hpp"
#include "gemm/gemm_backend.hpp"

namespace mipnerf::gemm {

using KernelParameters = std::map<std::string, size_t>;     // one CLBlast kernel's full parameter set
using ParameterSet = std::map<std::string, KernelParameters>;  // CLBlast kernel name → its parameters

// The MLP's three kinds of products (row-major): forward Y = X·W, backward data dX = dY·Wᵀ, backward
// weights dW = Xᵀ·dY. Anything else is `other`.
enum class GemmKind { forward, backward_data, backward_weights, other };
GemmKind gemm_kind(const GemmShape& shape);
const char* gemm_kind_name(GemmKind kind);  // "forward", "backward_data", "backward_weights", "other"

// One product of the MLP and how often a training step runs it per chunk and level.
struct GemmProblem {
  GemmShape shape;
  size_t count = 1;
  std::string label;  // e.g. "forward 65536x256x256"
  GemmKind kind() const { return gemm_kind(shape); }
  double flops() const { return 2.0 * static_cast<double>(shape.m) * shape.n * shape.k; }
};

// Adds the product m×k · k×n (op per ta, tb) to `problems`, `count` times: an equal shape already listed only counts
// up. The networks' list of products is built with it (mlp::mlp_gemm_problems).
void add_gemm_problem(std::vector<GemmProblem>& problems, size_t m, size_t n, size_t k, bool ta, bool tb, size_t count);

// What `mipnerf-cl tune` found for one device.
struct GemmTuning {
  std::string device_name;
  std::string driver_version;
  std::string clblast_version;
  ParameterSet common;                        // applied for every product
  std::map<GemmKind, ParameterSet> per_kind;  // applied (over common) before products of that kind
  std::string report_json = "{}";             // what tune measured, for people (JSON object text)
  // The backend gemm_backend=auto takes on this device: the faster of the backends it supports, timed by tune on the
  // whole network (forward + backward of one chunk); none: resolve_gemm_backend's rule. With its measurement.
  std::optional<GemmBackend> auto_backend;
  std::string backend_measurement_json = "{}";
  // The host MLP's CPU GEMM library per product (label → library; cpu_sgemm.hpp), timed by tune in the host MLP's
  // thread arrangement, with its measurement. Empty: OpenBLAS for every product.
  std::map<std::string, std::string> host_libraries;
  std::string host_libraries_measurement_json = "{}";
};

// $XDG_CACHE_HOME/mipnerf-cl, else $HOME/.cache/mipnerf-cl.
std::string tuning_cache_dir();
// <cache dir>/gemm-<device>-<driver>-clblast-<version>.json (unsafe characters replaced by '_').
std::string tuning_file_path(const ocl::DeviceInfo& device);

std::string to_json(const GemmTuning& tuning);
// Throws mipnerf::Error naming `where` and what is wrong.
GemmTuning tuning_from_json(const std::string& text, const std::string& where);
// Writes atomically (temporary beside it, then rename), creating the folder.
void save_tuning(const std::string& path, const GemmTuning& tuning);
// Whether `tuning` was measured for `device` with its driver version and this process's CLBlast version.
bool tuning_matches(const GemmTuning& tuning, const ocl::DeviceInfo& device);
// std::nullopt when the file does not exist; throws for an unreadable or malformed one.
std::optional<GemmTuning> read_tuning(const std::string& path);

// Installs parameters for the context's device: `common` is overridden now, the per-kind sets whenever
// gemm() switches kind. Throws when CLBlast refuses a kernel name or a set (then nothing stays installed).
void install_gemm_tuning(ocl::Context& ctx, const GemmTuning& tuning);
// Puts every kernel this process overrode back to CLBlast's database defaults for the device.
void clear_gemm_tuning(ocl::Context& ctx);
// Whether parameters are installed for the context's device.
bool gemm_tuning_installed(const ocl::Context& ctx);

// Loads tuning_file_path(device) when it exists and matches this device, driver and CLBlast (logging what it
// loaded); otherwise CLBlast's defaults stay and it logs once per device that `mipnerf-cl tune` would help. Returns whether a file was loaded.
bool load_gemm_tuning(ocl::Context& ctx);

// The CLBlast backend's preparation, called once per network by mlp::DeviceNetwork: load_gemm_tuning, unless
// parameters are installed for the context's device already (by an earlier network, or by tune or a benchmark that
// installed its own). So no caller loads the tuning: a network that runs its products on CLBlast has it.
void prepare_clblast_tuning(ocl::Context& ctx);

// The host MLP's library choice for this device from its tuning file (tuning_file_path), empty when there is none
// or it was made for another device or driver. Choices naming a library this build does not have are dropped with
// one line on stderr (a rebuild without it must not stop a run).
HostProductLibraries host_product_libraries_for(const ocl::DeviceInfo& device);

// Called by gemm() before each product: applies the installed set for `kind` if it is not applied yet.
void select_gemm_kind(ocl::Context& ctx, GemmKind kind);

}  // namespace mipnerf::gemm
