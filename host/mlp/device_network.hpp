// The network on the device (gemm_backend=clblast, any device): every product through CLBlast on the queue, with the
// element-wise kernels of kernels/mlp.cl between them (bias + ReLU after each product; the ReLU mask fused with the
// bias sums before each backward product). Made by make_network (network.hpp).
#pragma once

#include <memory>
#include <vector>

#include "mlp/network.hpp"

namespace mipnerf::ops {
class MlpKernels;
}

namespace mipnerf::mlp {

// A DeviceNetwork's buffers in a workspace, all on the device.
struct DeviceWorkspace : WorkspaceBuffers {
  DeviceWorkspace(ocl::Context& ctx, const MlpConfig& config, size_t max_rows, size_t max_rays, WorkspaceMode mode);
  // Bytes of the buffers below for a workspace of this size and mode.
  static size_t bytes_for(const MlpConfig& config, size_t max_rows, size_t max_rays, WorkspaceMode mode);

  std::vector<ocl::DeviceArray<float>> activations;  // training: one [rows][width] per trunk layer; inference: 2
                                                     // ping-pong [rows][widest hidden layer]
  ocl::DeviceArray<float> bottleneck;                // [rows][bottleneck_width] (training, view dependence)
  ocl::DeviceArray<float> view_hidden;               // [rows][view_branch_width] (training, view dependence)
  ocl::DeviceArray<float> ray_term;                  // [rays][view_branch_width]: the per-ray view product
  ocl::DeviceArray<float> grad_a, grad_b;            // [rows][widest hidden layer]: backward ping-pong (training)
  ocl::DeviceArray<float> partials;                  // [blocks or rays][widest layer]: column sums (training)
};

class DeviceNetwork : public Network {
 public:
  DeviceNetwork(ocl::Context& ctx, const MlpConfig& config);
  ~DeviceNetwork() override;
  gemm::GemmBackend backend() const override { return gemm::GemmBackend::clblast; }

 protected:
  std::unique_ptr<WorkspaceBuffers> make_workspace_buffers(size_t max_rows, size_t max_rays,
                                                           WorkspaceMode mode) const override;
  void forward_impl(const MlpInputs& in, const MlpOutputs& out, Workspace& ws, bool save) override;
  void backward_impl(const MlpInputs& in, Workspace& ws, const MlpOutputGradients& d_out,
                     const MatrixView& d_features) override;

 private:
  void trunk_forward(const MlpInputs& in, DeviceWorkspace& ws, bool save);
  void heads_forward(const MlpInputs& in, const MlpOutputs& out, DeviceWorkspace& ws, bool save);
  void heads_backward(const MlpInputs& in, DeviceWorkspace& ws, const MlpOutputGradients& d_out);
  void trunk_backward(const MlpInputs& in, DeviceWorkspace& ws, const MatrixView& d_features);
  void features_gradient(const MatrixView& dz, const DenseLayer& layer, size_t first_row, size_t rows,
                         const MatrixView& d_features, bool& written);
  void bias_gradient(const MatrixView& dz, const MatrixView* act, size_t rows, size_t cols, size_t bias_offset,
                     DeviceWorkspace& ws);

  std::unique_ptr<ops::MlpKernels> kernels_;
};

}  // namespace mipnerf::mlp
