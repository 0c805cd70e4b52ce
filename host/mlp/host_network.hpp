// The network on the host CPU (gemm_backend=host; devices whose buffers live in host memory,
// CL_DEVICE_HOST_UNIFIED_MEMORY): forward and backward fused block by block on the host (host_mlp.hpp), the products
// on the host BLAS, over the device's own buffers mapped in place (gemm/mapped_buffers.hpp). Made by make_network.
#pragma once

#include <memory>
#include <vector>

#include "gemm/mapped_buffers.hpp"
#include "mlp/host_mlp.hpp"
#include "mlp/network.hpp"

namespace mipnerf::mlp {

// 256-row blocks, one thread per compute unit of ctx's device, tune's CPU GEMM library per product when the device's
// tuning file has them.
HostMlpOptions default_host_options(const ocl::Context& ctx);

// A HostNetwork's buffers in a workspace: what a training forward keeps for the backward, in device buffers that the
// host maps (activation gradients stay in per-thread host scratch; an inference workspace holds nothing).
struct HostWorkspace : WorkspaceBuffers {
  HostWorkspace(ocl::Context& ctx, const MlpConfig& config, size_t max_rows, WorkspaceMode mode);
  std::vector<ocl::DeviceArray<float>> trunk;  // training: one [rows][width] per trunk layer
  ocl::DeviceArray<float> bottleneck;          // [rows][bottleneck_width] (training, view dependence)
  ocl::DeviceArray<float> view_hidden;         // [rows][view_branch_width] (training, view dependence)
};

class HostNetwork : public Network {
 public:
  HostNetwork(ocl::Context& ctx, const MlpConfig& config, const HostMlpOptions& options);
  gemm::GemmBackend backend() const override { return gemm::GemmBackend::host; }
  const HostMlpOptions& host_options() const { return host_.options(); }

 protected:
  std::unique_ptr<WorkspaceBuffers> make_workspace_buffers(size_t max_rows, size_t max_rays,
                                                           WorkspaceMode mode) const override;
  // Map what the pass reads and writes (blocking: the kernels that wrote the features have finished), run it on the
  // host, unmap (the kernels enqueued next see the outputs).
  void forward_impl(const MlpInputs& in, const MlpOutputs& out, Workspace& ws, bool save) override;
  void backward_impl(const MlpInputs& in, Workspace& ws, const MlpOutputGradients& d_out,
                     const MatrixView& d_features) override;

 private:
  void need_host_buffers(gemm::MappedBuffers& mapped, const MlpInputs& in, const HostWorkspace* saved,
                         bool write) const;
  HostForwardBuffers host_buffers(const gemm::MappedBuffers& mapped, const MlpInputs& in,
                                  const HostWorkspace* saved) const;

  HostMlp host_;
};

// A HostNetwork with `options` (blocks, threads, libraries) instead of default_host_options: the host backend chosen
// as make_network chooses it (gemm::choose_gemm_backend: refused where it cannot run; the BLAS's threads set).
std::unique_ptr<Network> make_host_network(ocl::Context& ctx, const MlpConfig& config, const HostMlpOptions& options);

}  // namespace mipnerf::mlp
