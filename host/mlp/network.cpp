// The network interface's shared part: parameters, gradients, workspaces, the checks of every call, and the factory
// that picks a backend.
#include "mlp/network.hpp"

#include <algorithm>
#include <string>

#include "core/error.hpp"
#include "mlp/device_network.hpp"
#include "mlp/host_network.hpp"

namespace mipnerf::mlp {
// ---- Workspace ----

WorkspaceBuffers::~WorkspaceBuffers() = default;

Workspace::Workspace(const MlpConfig& config, size_t max_rows, size_t max_rays, WorkspaceMode mode,
                     std::unique_ptr<WorkspaceBuffers> buffers)
    : config_(config), mode_(mode), max_rows_(max_rows), max_rays_(max_rays), buffers_(std::move(buffers)) {}

size_t Workspace::bytes_for(const MlpConfig& config, size_t max_rows, size_t max_rays, WorkspaceMode mode) {
  return DeviceWorkspace::bytes_for(config, max_rows, max_rays, mode);  // the largest (see network.hpp)
}

void Workspace::throw_made_by_another_backend(const char* where) {
  throw Error(std::string("MLP ") + where +
              ": the workspace was made by a network on another GEMM backend (its buffers are that backend's); make "
              "each network's workspaces with its own make_workspace");
}

// ---- Network ----

Network::Network(ocl::Context& ctx, const MlpConfig& config)
    : ctx_(&ctx),
      config_(config),
      layout_(parameter_layout(config)),
      params_(ctx, layout_.total, "mlp parameters [flat]"),
      grads_(ctx, layout_.total, "mlp gradients [flat]") {
  params_.upload(ctx, initial_parameters(config));
  zero_grad();
}

Network::~Network() = default;

size_t Network::bytes_for(const MlpConfig& config) { return 2 * parameter_layout(config).total * sizeof(float); }

std::vector<float> Network::download_params() const { return params_.download(*ctx_); }

void Network::upload_params(const std::vector<float>& values) {
  if (values.size() != layout_.total) {
    throw Error("MLP: " + std::to_string(values.size()) + " parameter values given, the network (" + describe(config_) +
                ") has " + std::to_string(layout_.total));
  }
  params_.upload(*ctx_, values);
}

std::vector<float> Network::download_grads() const { return grads_.download(*ctx_); }

void Network::zero_grad() { grads_.fill(*ctx_, 0.0f); }

Workspace Network::make_workspace(size_t max_rows, size_t max_rays, WorkspaceMode mode) const {
  config_.validate();
  if (max_rows == 0 || max_rays == 0) throw Error("MLP workspace: max_rows and max_rays must be positive");
  return Workspace(config_, max_rows, max_rays, mode, make_workspace_buffers(max_rows, max_rays, mode));
}

void Network::check_inputs(const MlpInputs& in, const Workspace& ws, const char* where) const {
  const std::string w = std::string("MLP ") + where;
  const MlpConfig& c = ws.config_;
  if (c.input_width != config_.input_width || c.depth != config_.depth || c.width != config_.width ||
      c.view_dependence != config_.view_dependence || c.view_width != config_.view_width ||
      c.view_branch_width != config_.view_branch_width || c.bottleneck_width != config_.bottleneck_width) {
    throw Error(w + ": the workspace was made for another MLP configuration (" + describe(c) + ")");
  }
  if (in.n_rays == 0 || in.samples_per_ray == 0) throw Error(w + ": empty chunk (0 rays or 0 samples per ray)");
  if (in.rows() > ws.max_rows_ || in.n_rays > ws.max_rays_) {
    throw Error(w + ": chunk of " + std::to_string(in.n_rays) + " rays × " + std::to_string(in.samples_per_ray) +
                " samples exceeds the workspace (" + std::to_string(ws.max_rays_) + " rays, " +
                std::to_string(ws.max_rows_) + " rows); use smaller chunks or a bigger workspace");
  }
  if (in.features.array == nullptr) throw Error(w + ": no features buffer");
  if (config_.view_dependence && in.view_encoding.array == nullptr) {
    throw Error(w + ": the MLP is view-dependent but no view encoding [rays][" + std::to_string(config_.view_width) +
                "] was given");
  }
  // Both backends read these directly (the host one through mapped pointers): sizes are checked here, once.
  ocl::require_matrix(in.features, in.rows(), config_.input_width, "features", w);
  if (config_.view_dependence) ocl::require_matrix(in.view_encoding, in.n_rays, config_.view_width, "view_encoding", w);
}

void Network::forward(const MlpInputs& in, const MlpOutputs& out, Workspace& ws) {
  check_inputs(in, ws, "forward");
  ocl::require_matrix(out.raw_density, in.rows(), config_.density_outputs, "raw_density", "MLP forward");
  const bool save = ws.mode_ == WorkspaceMode::training;
  if (out.raw_rgb.array != nullptr) {
    ocl::require_matrix(out.raw_rgb, in.rows(), config_.rgb_outputs, "raw_rgb", "MLP forward");
  } else if (save) {
    throw Error(
        "MLP forward: no raw_rgb output given to a training workspace (a density-only forward is for inference: the "
        "backward needs the colour head's activations)");
  }
  ws.has_forward_ = false;
  forward_impl(in, out, ws, save);
  if (save) {
    ws.inputs_ = in;
    ws.has_forward_ = true;
  }
}

namespace {

// Whether two matrices of `rows` rows share an element's storage (a conservative test: their spans in one buffer).
bool spans_overlap(const MatrixView& a, size_t a_cols, const MatrixView& b, size_t b_cols, size_t rows) {
  if (a.array == nullptr || b.array == nullptr || a.array->raw() != b.array->raw() || rows == 0) return false;
  const size_t a_end = a.offset + (rows - 1) * a.ld + a_cols, b_end = b.offset + (rows - 1) * b.ld + b_cols;
  return a.offset < b_end && b.offset < a_end;
}

}  // namespace

void Network::backward(Workspace& ws, const MlpOutputGradients& d_out, MatrixView d_features) {
  if (ws.mode_ != WorkspaceMode::training) {
    throw Error(
        "MLP backward: the workspace is an inference workspace (it keeps no activations); make it with "
        "WorkspaceMode::training");
  }
  if (!ws.has_forward_) throw Error("MLP backward: no forward has been run through this workspace");
  check_inputs(ws.inputs_, ws, "backward");
  ocl::require_matrix(d_out.d_raw_density, ws.inputs_.rows(), config_.density_outputs, "d_raw_density", "MLP backward");
  ocl::require_matrix(d_out.d_raw_rgb, ws.inputs_.rows(), config_.rgb_outputs, "d_raw_rgb", "MLP backward");
  if (d_features.array != nullptr) {
    ocl::require_matrix(d_features, ws.inputs_.rows(), config_.input_width, "d_features", "MLP backward");
    // The backward reads the features after it has begun writing their gradient (the host one block by block).
    if (spans_overlap(d_features, config_.input_width, ws.inputs_.features, config_.input_width, ws.inputs_.rows())) {
      throw Error("MLP backward: d_features ('" + d_features.array->name() +
                  "') overlaps the features it is the gradient of; give it a buffer (or range) of its own");
    }
  }
  backward_impl(ws.inputs_, ws, d_out, d_features);
}

std::unique_ptr<Network> make_network(ocl::Context& ctx, const MlpConfig& config, gemm::GemmBackend backend) {
  switch (gemm::choose_gemm_backend(ctx, backend)) {
    case gemm::GemmBackend::clblast:
      return std::make_unique<DeviceNetwork>(ctx, config);
    case gemm::GemmBackend::host:
      return std::make_unique<HostNetwork>(ctx, config, default_host_options(ctx));
    case gemm::GemmBackend::automatic:
      break;  // choose_gemm_backend never returns it
  }
  throw Error(std::string("internal error: gemm backend '") + enum_name(backend) + "' has no network");
}

std::vector<Network*> network_pointers(const std::vector<std::unique_ptr<Network>>& networks) {
  std::vector<Network*> out;
  for (const auto& n : networks) out.push_back(n.get());
  return out;
}

}  // namespace mipnerf::mlp
