// The MLP as one interface over its backends (tiny-cuda-nn's Network, chosen once by a factory): a Network holds the
// flat parameters and gradients on the device and runs forward and backward of chunks of samples through
// workspaces; DeviceNetwork (device_network.hpp) runs every product through CLBlast on the device, HostNetwork
// (host_network.hpp) the whole MLP fused on the host CPU over the device's own buffers. make_network picks one.
//
// Use in training (one chunk of rays at a time; coarse and fine share one network, so their gradients add up):
//   net.zero_grad();
//   for each chunk: net.forward(in_coarse, out_coarse, ws_coarse); … net.forward(in_fine, out_fine, ws_fine);
//                   … net.backward(ws_fine, d_fine); net.backward(ws_coarse, d_coarse);
//   stats = adam.gradient_stats(net.grads()); if (stats.finite()) adam.step(net.params(), net.grads(), lr, &stats);
// A workspace holds one forward's saved activations until its backward: use one per forward that is still
// waiting for its backward (e.g. one per level). Rendering uses an inference workspace (no saved activations).
// The NeRF baseline's two networks are two Network instances.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "gemm/gemm_backend.hpp"
#include "mlp/mlp_config.hpp"

namespace mipnerf::mlp {

using ocl::MatrixView;
using ocl::view;

// One chunk of samples: n_rays rays × samples_per_ray samples = rows, ray-major (row = ray·N + sample).
struct MlpInputs {
  MatrixView features;       // [rows][input_width] (ld ≥ input_width), e.g. ipe_features
  MatrixView view_encoding;  // [n_rays][view_width], PER RAY; ignored (may be empty) without view dependence
  size_t n_rays = 0;
  size_t samples_per_ray = 0;
  size_t rows() const { return n_rays * samples_per_ray; }
};

// Where the forward writes (CLBlast writes into these views directly, no copies).
struct MlpOutputs {
  MatrixView raw_density;  // [rows][density_outputs]; the shared `raw_density [rows]` layout is ld = 1
  // [rows][rgb_outputs]; no array (inference only): density only, the colour head (view branch, rgb layer) skipped,
  // for a level whose colour nothing reads (graph.hpp)
  MatrixView raw_rgb;
};

// ∂loss/∂outputs of one forward, read only.
struct MlpOutputGradients {
  MatrixView d_raw_density;  // [rows][density_outputs]
  MatrixView d_raw_rgb;      // [rows][rgb_outputs]
};

enum class WorkspaceMode {
  training,   // saves every activation the backward needs
  inference,  // forward only: no saved activations (at most ping-pong buffers), no backward
};

// A backend's own memory in a workspace (the activations its forward saves, its backward's buffers), made by the
// network of that backend (Network::make_workspace_buffers); no other code reads it.
class WorkspaceBuffers {
 public:
  virtual ~WorkspaceBuffers();
};

// Memory for forwards (and backwards) of up to max_rows samples from up to max_rays rays: what every backend's
// workspace has (its size, mode, and the forward waiting for its backward), and the backend's own buffers.
class Workspace {
 public:
  Workspace(const MlpConfig& config, size_t max_rows, size_t max_rays, WorkspaceMode mode,
            std::unique_ptr<WorkspaceBuffers> buffers);

  // Bytes a workspace of this size takes, to choose a chunk size that fits the device: an upper bound over the
  // backends (the device network's, whose backward buffers live on the device too).
  static size_t bytes_for(const MlpConfig& config, size_t max_rows, size_t max_rays, WorkspaceMode mode);

  // Movable, not copyable (a copy would share the device buffers).
  Workspace(Workspace&&) = default;
  Workspace& operator=(Workspace&&) = default;
  Workspace(const Workspace&) = delete;
  Workspace& operator=(const Workspace&) = delete;

  WorkspaceMode mode() const { return mode_; }
  size_t max_rows() const { return max_rows_; }
  size_t max_rays() const { return max_rays_; }

  // The backend's buffers, as that backend knows them. Throws mipnerf::Error naming `where` when another backend's
  // network made this workspace (make each network's workspaces with its own make_workspace).
  template <class Buffers>
  Buffers& buffers(const char* where) {
    auto* own = dynamic_cast<Buffers*>(buffers_.get());
    if (own == nullptr) throw_made_by_another_backend(where);
    return *own;
  }

 private:
  friend class Network;  // the checks and the forward waiting for its backward, common to every backend
  [[noreturn]] static void throw_made_by_another_backend(const char* where);
  MlpConfig config_;
  WorkspaceMode mode_;
  size_t max_rows_, max_rays_;
  std::unique_ptr<WorkspaceBuffers> buffers_;
  // The forward waiting for its backward: its inputs (the caller keeps them alive and unchanged) and size.
  bool has_forward_ = false;
  MlpInputs inputs_;
};

class Network {
 public:
  virtual ~Network();
  Network(const Network&) = delete;
  Network& operator=(const Network&) = delete;

  // Bytes a network of `config` takes on the device: its parameters and its gradients (workspaces aside).
  static size_t bytes_for(const MlpConfig& config);

  // The backend that runs this network's products (clblast or host; never automatic).
  virtual gemm::GemmBackend backend() const = 0;

  const MlpConfig& config() const { return config_; }
  const ParameterLayout& layout() const { return layout_; }
  size_t parameter_count() const { return layout_.total; }

  // The flat buffers, layout() order: what Adam updates and what a checkpoint stores.
  ocl::DeviceArray<float>& params() { return params_; }
  const ocl::DeviceArray<float>& params() const { return params_; }
  ocl::DeviceArray<float>& grads() { return grads_; }
  const ocl::DeviceArray<float>& grads() const { return grads_; }
  std::vector<float> download_params() const;
  void upload_params(const std::vector<float>& values);  // size must be parameter_count()
  std::vector<float> download_grads() const;

  // A workspace with this network's backend's buffers (another backend's network refuses it).
  Workspace make_workspace(size_t max_rows, size_t max_rays, WorkspaceMode mode) const;

  // Enqueues the forward of one chunk. In a training workspace, saves what backward() needs and remembers
  // `in` (whose buffers must stay unchanged until then). Throws mipnerf::Error for sizes that do not fit.
  void forward(const MlpInputs& in, const MlpOutputs& out, Workspace& ws);

  // Enqueues the backward of the last forward through `ws`: grads += ∂loss/∂params (beta = 1, so chunks,
  // levels and passes accumulate until zero_grad()).
  // d_features [rows][input_width] (ld ≥ input_width), optional: when given, the backward also OVERWRITES it with
  // ∂loss/∂features of that forward — the first trunk layer's input gradient plus, for every skip layer, the
  // gradient through its input rows that take the features — for an encoding with parameters of its own before the
  // MLP (Zip-NeRF's hash grid). It must not overlap the features. Not given (empty view, the default): no gradient
  // flows to the features, and the backward runs exactly the products it would without this argument (mip-NeRF's
  // integrated encoding has no parameters).
  void backward(Workspace& ws, const MlpOutputGradients& d_out, MatrixView d_features = {});

  void zero_grad();

 protected:
  // Parameters from initial_parameters(config); gradients zero.
  Network(ocl::Context& ctx, const MlpConfig& config);
  // The backend's buffers for a workspace of this size and mode.
  virtual std::unique_ptr<WorkspaceBuffers> make_workspace_buffers(size_t max_rows, size_t max_rays,
                                                                   WorkspaceMode mode) const = 0;
  virtual void forward_impl(const MlpInputs& in, const MlpOutputs& out, Workspace& ws, bool save) = 0;
  // `in`: what the forward through `ws` read (checked again, unchanged sizes). d_features: as backward(), checked
  // (its array null: not asked for).
  virtual void backward_impl(const MlpInputs& in, Workspace& ws, const MlpOutputGradients& d_out,
                             const MatrixView& d_features) = 0;

  ocl::Context* ctx_;
  MlpConfig config_;
  ParameterLayout layout_;
  ocl::DeviceArray<float> params_;
  ocl::DeviceArray<float> grads_;

 private:
  void check_inputs(const MlpInputs& in, const Workspace& ws, const char* where) const;
};

// A network of `config` on ctx's device, its products on `backend` (automatic: tune's measurement for the device,
// else the rule of gemm::resolve_gemm_backend; logged through the context), each backend prepared by its own
// constructor (CLBlast's: the device's tuned parameters; the host's: tune's CPU GEMM library per product). Throws
// mipnerf::Error when the backend cannot run on the device or in this build, saying why and what to do.
// (A host network with other blocks or threads: mlp::make_host_network, host_network.hpp.)
std::unique_ptr<Network> make_network(ocl::Context& ctx, const MlpConfig& config, gemm::GemmBackend backend);

// Raw pointers to a list of networks, as the graph and the renderer take them.
std::vector<Network*> network_pointers(const std::vector<std::unique_ptr<Network>>& networks);

}  // namespace mipnerf::mlp
