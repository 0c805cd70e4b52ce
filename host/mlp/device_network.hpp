// The network on the device (gemm_backend=clblast, any device): every product through CLBlast on the queue, with the
// element-wise kernels of kernels/mlp.cl between them (bias + ReLU after each product; the ReLU mask fused with the
// bias sums before each backward product). Made by make_network (network.hpp).
#pragma once

#include <memory>

#include "mlp/network.hpp"

namespace mipnerf::ops {
class MlpKernels;
}

namespace mipnerf::mlp {

class DeviceNetwork : public Network {
 public:
  DeviceNetwork(ocl::Context& ctx, const MlpConfig& config);
  ~DeviceNetwork() override;
  gemm::GemmBackend backend() const override { return gemm::GemmBackend::clblast; }

 protected:
  bool device_backward_buffers() const override { return true; }
  void forward_impl(const MlpInputs& in, const MlpOutputs& out, Workspace& ws, bool save) override;
  void backward_impl(Workspace& ws, const MlpOutputGradients& d_out) override;

 private:
  void trunk_forward(const MlpInputs& in, Workspace& ws, bool save);
  void heads_forward(const MlpInputs& in, const MlpOutputs& out, Workspace& ws, bool save);
  void heads_backward(Workspace& ws, const MlpOutputGradients& d_out);
  void trunk_backward(Workspace& ws);
  void bias_gradient(const MatrixView& dz, const MatrixView* act, size_t rows, size_t cols, size_t bias_offset,
                     Workspace& ws);

  std::unique_ptr<ops::MlpKernels> kernels_;
};

}  // namespace mipnerf::mlp
