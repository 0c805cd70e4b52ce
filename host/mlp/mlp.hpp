// The MLP on the device: every product through CLBlast (row-major, rows = samples), bias/activation kernels
// around them, flat parameter and gradient buffers, and a workspace per chunk that bounds memory.
//
// Use in training (one chunk of rays at a time; coarse and fine share one Mlp, so their gradients add up):
//   mlp.zero_grad();
//   for each chunk: mlp.forward(in_coarse, out_coarse, ws_coarse); … mlp.forward(in_fine, out_fine, ws_fine);
//                   … mlp.backward(ws_fine, d_fine); mlp.backward(ws_coarse, d_coarse);
//   stats = adam.gradient_stats(mlp.grads()); if (stats.finite()) adam.step(mlp.params(), mlp.grads(), lr, &stats);
// A workspace holds one forward's saved activations until its backward: use one per forward that is still
// waiting for its backward (e.g. one per level). Rendering uses an inference workspace (no saved activations).
// The NeRF baseline's two networks are two Mlp instances.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "mlp/gemm.hpp"
#include "mlp/host_mlp.hpp"
#include "mlp/mlp_config.hpp"

namespace mipnerf::ops {
class MlpKernels;
}

namespace mipnerf::mlp {

class MappedBuffers;

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
  MatrixView raw_rgb;      // [rows][rgb_outputs]
};

// ∂loss/∂outputs of one forward, read only.
struct MlpOutputGradients {
  MatrixView d_raw_density;  // [rows][density_outputs]
  MatrixView d_raw_rgb;      // [rows][rgb_outputs]
};

enum class WorkspaceMode {
  training,   // saves every activation the backward needs
  inference,  // forward only: two ping-pong buffers, no backward
};

// Device memory for forwards (and backwards) of up to max_rows samples from up to max_rays rays.
class Workspace {
 public:
  Workspace(ocl::Context& ctx, const MlpConfig& config, size_t max_rows, size_t max_rays, WorkspaceMode mode);

  // Bytes a workspace of this size takes, to choose a chunk size that fits the device (an upper bound: on the host
  // path, gemm_backend=host, the device backward buffers are not allocated).
  static size_t bytes_for(const MlpConfig& config, size_t max_rows, size_t max_rays, WorkspaceMode mode);

  // Movable, not copyable (a copy would share the device buffers).
  Workspace(Workspace&&) = default;
  Workspace& operator=(Workspace&&) = default;
  Workspace(const Workspace&) = delete;
  Workspace& operator=(const Workspace&) = delete;

  WorkspaceMode mode() const { return mode_; }
  size_t max_rows() const { return max_rows_; }
  size_t max_rays() const { return max_rays_; }

 private:
  friend class Mlp;
  MlpConfig config_;
  WorkspaceMode mode_;
  size_t max_rows_, max_rays_;
  size_t max_cols_;                                   // widest hidden layer
  std::vector<ocl::DeviceArray<float>> activations_;  // training: one [rows][width] per trunk layer; inference: 2
  ocl::DeviceArray<float> bottleneck_;                // [rows][bottleneck_width] (training, view dependence)
  ocl::DeviceArray<float> view_hidden_;               // [rows][view_branch_width] (training, view dependence)
  ocl::DeviceArray<float> ray_term_;                  // [rays][view_branch_width]: the per-ray view product
  bool device_backward_ = false;                      // the device path's backward buffers below exist
  ocl::DeviceArray<float> grad_a_, grad_b_;           // [rows][max_cols]: backward ping-pong (training, device path)
  ocl::DeviceArray<float> partials_;                  // [blocks or rays][max_cols]: column sums (training)
  // The forward waiting for its backward: its inputs (the caller keeps them alive and unchanged) and size.
  bool has_forward_ = false;
  MlpInputs inputs_;
};

class Mlp {
 public:
  // Parameters from glorot_uniform_init(config); gradients zero.
  Mlp(ocl::Context& ctx, const MlpConfig& config);
  ~Mlp();
  // Bytes a network of `config` takes on the device: its parameters and its gradients (workspaces aside).
  static size_t bytes_for(const MlpConfig& config);
  Mlp(const Mlp&) = delete;
  Mlp& operator=(const Mlp&) = delete;

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

  Workspace make_workspace(size_t max_rows, size_t max_rays, WorkspaceMode mode) const;

  // Enqueues the forward of one chunk. In a training workspace, saves what backward() needs and remembers
  // `in` (whose buffers must stay unchanged until then). Throws mipnerf::Error for sizes that do not fit.
  void forward(const MlpInputs& in, const MlpOutputs& out, Workspace& ws);

  // Enqueues the backward of the last forward through `ws`: grads += ∂loss/∂params (beta = 1, so chunks,
  // levels and passes accumulate until zero_grad()). No gradient flows to the features (they have no
  // parameters before the MLP).
  void backward(Workspace& ws, const MlpOutputGradients& d_out);

  void zero_grad();

  // How the host path (gemm_backend=host: the whole MLP fused on the host, host_mlp.hpp) splits its work: rows per
  // block and threads. Default: 256 rows, one thread per compute unit of the device.
  void set_host_options(const HostMlpOptions& options);
  HostMlpOptions host_options() const;

 private:
  void check_inputs(const MlpInputs& in, const Workspace& ws, const char* where) const;
  void trunk_forward(const MlpInputs& in, Workspace& ws, bool save);
  void heads_forward(const MlpInputs& in, const MlpOutputs& out, Workspace& ws, bool save);
  void heads_backward(Workspace& ws, const MlpOutputGradients& d_out);
  void trunk_backward(Workspace& ws);
  HostMlp& host_mlp();
  void need_host_buffers(MappedBuffers& mapped, const MlpInputs& in, const Workspace& ws, bool activations,
                         bool write) const;
  HostForwardBuffers host_buffers(const MappedBuffers& mapped, const MlpInputs& in, const Workspace& ws,
                                  bool activations) const;
  void host_forward(const MlpInputs& in, const MlpOutputs& out, Workspace& ws, bool save);
  void host_backward(Workspace& ws, const MlpOutputGradients& d_out);
  void bias_gradient(const MatrixView& dz, const MatrixView* act, size_t rows, size_t cols, size_t bias_offset,
                     Workspace& ws);

  ocl::Context* ctx_;
  MlpConfig config_;
  ParameterLayout layout_;
  ocl::DeviceArray<float> params_;
  ocl::DeviceArray<float> grads_;
  std::unique_ptr<ops::MlpKernels> kernels_;
  std::unique_ptr<HostMlp> host_;  // made on first use by the host path
};

}  // namespace mipnerf::mlp
