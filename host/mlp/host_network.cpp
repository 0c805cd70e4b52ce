// The host network: the whole MLP fused on the host CPU (host_mlp.hpp) over the device's buffers, mapped.
#include "mlp/host_network.hpp"

#include <algorithm>
#include <chrono>
#include <string>

#include "gemm/gemm_backend.hpp"
#include "gemm/gemm_tuning.hpp"
#include "gemm/mapped_buffers.hpp"

namespace mipnerf::mlp {

HostMlpOptions default_host_options(const ocl::Context& ctx) {
  HostMlpOptions o;
  o.threads = std::max<size_t>(1, ctx.device_info().compute_units);
  o.libraries = gemm::host_product_libraries_for(ctx.device_info());  // tune's per-product choice, if any
  return o;
}

HostWorkspace::HostWorkspace(ocl::Context& ctx, const MlpConfig& config, size_t max_rows, WorkspaceMode mode) {
  if (mode != WorkspaceMode::training) return;  // inference: per-thread host scratch only
  for (size_t i = 0; i < config.depth; ++i) {
    trunk.emplace_back(ctx, max_rows * config.width, "mlp activation of trunk " + std::to_string(i) + " [rows][width]");
  }
  if (config.view_dependence) {
    bottleneck = ocl::DeviceArray<float>(ctx, max_rows * config.bottleneck_width, "mlp bottleneck [rows][width]");
    view_hidden = ocl::DeviceArray<float>(ctx, max_rows * config.view_branch_width,
                                          "mlp view-branch activation [rows][view_branch_width]");
  }
}

HostNetwork::HostNetwork(ocl::Context& ctx, const MlpConfig& config, const HostMlpOptions& options)
    : Network(ctx, config), host_(config, options) {}

std::unique_ptr<Network> make_host_network(ocl::Context& ctx, const MlpConfig& config, const HostMlpOptions& options) {
  gemm::choose_gemm_backend(ctx, gemm::GemmBackend::host);
  return std::make_unique<HostNetwork>(ctx, config, options);
}

std::unique_ptr<WorkspaceBuffers> HostNetwork::make_workspace_buffers(size_t max_rows, size_t,
                                                                      WorkspaceMode mode) const {
  return std::make_unique<HostWorkspace>(*ctx_, config_, max_rows, mode);
}

namespace {

// A call's thread times as stage times: its wall time split in the proportions of its threads' time, each product
// kind under "gemm <kind>" with its FLOPs, the rest under the caller's stage.
void profile_host_call(ocl::Context& ctx, const HostMlpTimes& t, double wall_seconds) {
  ocl::StageProfiler* profiler = ctx.recording_profiler();
  if (profiler == nullptr) return;
  const double scale = t.total() > 0 ? wall_seconds / t.total() : 0.0;
  auto add = [&](const char* stage, double seconds, double flops) {
    if (seconds <= 0 && flops <= 0) return;
    ocl::StageScope scope(ctx, stage);
    profiler->add_host_seconds(seconds * scale);
    profiler->add_flops(flops);
  };
  add("gemm forward", t.gemm_forward, t.flops_forward);
  add("gemm backward_data", t.gemm_backward_data, t.flops_backward_data);
  add("gemm backward_weights", t.gemm_backward_weights, t.flops_backward_weights);
  if (t.elementwise > 0) profiler->add_host_seconds(t.elementwise * scale);
}

}  // namespace

// What a host pass reads: the parameters, the inputs and, from `saved` (training), the activations the forward keeps
// for the backward. `write`: the activations are written (forward) or only read (backward).
void HostNetwork::need_host_buffers(gemm::MappedBuffers& mapped, const MlpInputs& in, const HostWorkspace* saved,
                                    bool write) const {
  mapped.need(&params_, false);
  mapped.need(in.features, false);
  mapped.need(in.view_encoding, false);
  if (saved == nullptr) return;
  for (const auto& a : saved->trunk) mapped.need(&a, write);
  if (config_.view_dependence) {
    mapped.need(&saved->bottleneck, write);
    mapped.need(&saved->view_hidden, write);
  }
}

HostForwardBuffers HostNetwork::host_buffers(const gemm::MappedBuffers& mapped, const MlpInputs& in,
                                             const HostWorkspace* saved) const {
  HostForwardBuffers b;
  b.params = mapped.at(&params_);
  b.features = mapped.at(in.features);
  b.features_ld = in.features.ld;
  b.view_encoding = config_.view_dependence ? mapped.at(in.view_encoding) : nullptr;
  b.view_ld = in.view_encoding.ld;
  if (saved != nullptr) {
    for (const auto& a : saved->trunk) b.trunk.push_back(mapped.at(&a));
    if (config_.view_dependence) {
      b.bottleneck = mapped.at(&saved->bottleneck);
      b.view_hidden = mapped.at(&saved->view_hidden);
    }
  }
  b.n_rays = in.n_rays;
  b.samples_per_ray = in.samples_per_ray;
  return b;
}

// Maps what the forward reads and writes (blocking: the kernels that wrote the features have finished), runs it on
// the host, and unmaps (the kernels enqueued next see the outputs). See mapped_buffers.hpp.
void HostNetwork::forward_impl(const MlpInputs& in, const MlpOutputs& out, Workspace& ws, bool save) {
  const HostWorkspace* saved = save ? &ws.buffers<HostWorkspace>("forward") : nullptr;
  gemm::MappedBuffers mapped(*ctx_, "the host MLP's forward");
  need_host_buffers(mapped, in, saved, true);
  mapped.need(out.raw_density, true);
  mapped.need(out.raw_rgb, true);
  mapped.map();
  const auto start = std::chrono::steady_clock::now();
  HostForwardBuffers b = host_buffers(mapped, in, saved);
  b.density = mapped.at(out.raw_density);
  b.density_ld = out.raw_density.ld;
  b.rgb = out.raw_rgb.array ? mapped.at(out.raw_rgb) : nullptr;  // null: density only
  b.rgb_ld = out.raw_rgb.ld;
  const HostMlpTimes times = host_.forward(b, ctx_->recording_profiler() != nullptr);
  profile_host_call(*ctx_, times, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
}

void HostNetwork::backward_impl(const MlpInputs& in, Workspace& ws, const MlpOutputGradients& d_out,
                                const MatrixView& d_features) {
  const HostWorkspace& saved = ws.buffers<HostWorkspace>("backward");
  gemm::MappedBuffers mapped(*ctx_, "the host MLP's backward");
  need_host_buffers(mapped, in, &saved, false);
  mapped.need(&grads_, true);
  mapped.need(d_out.d_raw_density, false);
  mapped.need(d_out.d_raw_rgb, false);
  mapped.need(d_features, true);  // an empty view (not asked for) maps nothing
  mapped.map();
  const auto start = std::chrono::steady_clock::now();
  HostBackwardBuffers b;
  b.saved = host_buffers(mapped, in, &saved);
  b.d_density = mapped.at(d_out.d_raw_density);
  b.d_density_ld = d_out.d_raw_density.ld;
  b.d_rgb = mapped.at(d_out.d_raw_rgb);
  b.d_rgb_ld = d_out.d_raw_rgb.ld;
  b.grads = mapped.at(&grads_);
  b.d_features = mapped.at(d_features);  // null when not asked for
  b.d_features_ld = d_features.ld;
  const HostMlpTimes times = host_.backward(b, ctx_->recording_profiler() != nullptr);
  profile_host_call(*ctx_, times, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
}

}  // namespace mipnerf::mlp
