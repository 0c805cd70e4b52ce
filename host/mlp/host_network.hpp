// The network on the host CPU (gemm_backend=host; devices whose buffers live in host memory,
// CL_DEVICE_HOST_UNIFIED_MEMORY): forward and backward fused block by block on the host (host_mlp.hpp), the products
// on the host BLAS, over the device's own buffers mapped in place (gemm/mapped_buffers.hpp). Made by make_network.
#pragma once

#include "gemm/mapped_buffers.hpp"
#include "mlp/host_mlp.hpp"
#include "mlp/network.hpp"

namespace mipnerf::mlp {

// 256-row blocks, one thread per compute unit of ctx's device.
HostMlpOptions default_host_options(const ocl::Context& ctx);

class HostNetwork : public Network {
 public:
  HostNetwork(ocl::Context& ctx, const MlpConfig& config, const HostMlpOptions& options);
  gemm::GemmBackend backend() const override { return gemm::GemmBackend::host; }
  const HostMlpOptions& host_options() const { return host_.options(); }

 protected:
  bool device_backward_buffers() const override { return false; }
  // Map what the pass reads and writes (blocking: the kernels that wrote the features have finished), run it on the
  // host, unmap (the kernels enqueued next see the outputs).
  void forward_impl(const MlpInputs& in, const MlpOutputs& out, Workspace& ws, bool save) override;
  void backward_impl(Workspace& ws, const MlpOutputGradients& d_out) override;

 private:
  void need_host_buffers(gemm::MappedBuffers& mapped, const MlpInputs& in, const Workspace& ws, bool activations,
                         bool write) const;
  HostForwardBuffers host_buffers(const gemm::MappedBuffers& mapped, const MlpInputs& in, const Workspace& ws,
                                  bool activations) const;

  HostMlp host_;
};

}  // namespace mipnerf::mlp
