// The device MLP: forward, backward and the workspace (see mlp.hpp for the calling pattern).
#include "mlp/mlp.hpp"

#include <algorithm>
#include <chrono>
#include <string>

#include "core/error.hpp"
#include "mlp/mapped_buffers.hpp"
#include "ops/mlp.hpp"

namespace mipnerf::mlp {
namespace {

size_t widest_hidden(const MlpConfig& c) {
  size_t w = c.width;
  if (c.view_dependence) w = std::max({w, c.bottleneck_width, c.view_branch_width});
  return w;
}

// Partials rows: blocks of kRowsPerBlock rows for bias gradients, or one per ray for the view branch.
size_t partial_rows(const MlpConfig& c, size_t max_rows, size_t max_rays) {
  const size_t blocks = ops::MlpKernels::blocks_for(max_rows, ops::MlpKernels::kRowsPerBlock);
  return c.view_dependence ? std::max(blocks, max_rays) : blocks;
}

size_t partial_cols(const MlpConfig& c) {
  return std::max({widest_hidden(c), c.density_outputs, c.rgb_outputs});
}

// The weights of `layer` from input row `first_row` on: a [rows][out] block of its [in][out] matrix.
MatrixView weights(const ocl::DeviceArray<float>& flat, const DenseLayer& layer, size_t first_row = 0) {
  return view(flat, layer.out, layer.weight_offset + first_row * layer.out);
}

}  // namespace

// ---- Workspace ----

Workspace::Workspace(ocl::Context& ctx, const MlpConfig& config, size_t max_rows, size_t max_rays,
                     WorkspaceMode mode)
    : config_(config), mode_(mode), max_rows_(max_rows), max_rays_(max_rays), max_cols_(widest_hidden(config)) {
  config.validate();
  if (max_rows == 0 || max_rays == 0) throw Error("MLP workspace: max_rows and max_rays must be positive");
  if (mode == WorkspaceMode::training) {
    for (size_t i = 0; i < config.depth; ++i) {
      activations_.emplace_back(ctx, max_rows * config.width,
                                "mlp activation of trunk " + std::to_string(i) + " [rows][width]");
    }
    if (config.view_dependence) {
      bottleneck_ = ocl::DeviceArray<float>(ctx, max_rows * config.bottleneck_width, "mlp bottleneck [rows][width]");
      view_hidden_ = ocl::DeviceArray<float>(ctx, max_rows * config.view_branch_width,
                                             "mlp view-branch activation [rows][view_branch_width]");
    }
    // The device path's backward buffers; the host path keeps activation gradients in per-thread scratch instead.
    device_backward_ = !ctx.gemm_on_host();
    if (device_backward_) {
      grad_a_ = ocl::DeviceArray<float>(ctx, max_rows * max_cols_, "mlp backward buffer A [rows][width]");
      grad_b_ = ocl::DeviceArray<float>(ctx, max_rows * max_cols_, "mlp backward buffer B [rows][width]");
      partials_ = ocl::DeviceArray<float>(ctx, partial_rows(config, max_rows, max_rays) * partial_cols(config),
                                          "mlp column-sum partials [blocks][width]");
    }
  } else {
    for (int i = 0; i < 2; ++i) {
      activations_.emplace_back(ctx, max_rows * max_cols_, "mlp inference buffer " + std::to_string(i) +
                                                               " [rows][width]");
    }
  }
  if (config.view_dependence) {
    ray_term_ = ocl::DeviceArray<float>(ctx, max_rays * config.view_branch_width,
                                        "mlp per-ray view product [rays][view_branch_width]");
  }
}

size_t Workspace::bytes_for(const MlpConfig& c, size_t max_rows, size_t max_rays, WorkspaceMode mode) {
  const size_t cols = widest_hidden(c);
  size_t floats = c.view_dependence ? max_rays * c.view_branch_width : 0;
  if (mode == WorkspaceMode::training) {
    floats += c.depth * max_rows * c.width + 2 * max_rows * cols +
              partial_rows(c, max_rows, max_rays) * partial_cols(c);
    if (c.view_dependence) floats += max_rows * (c.bottleneck_width + c.view_branch_width);
  } else {
    floats += 2 * max_rows * cols;
  }
  return floats * sizeof(float);
}

// ---- Mlp ----

Mlp::Mlp(ocl::Context& ctx, const MlpConfig& config)
    : ctx_(&ctx),
      config_(config),
      layout_(parameter_layout(config)),
      params_(ctx, layout_.total, "mlp parameters [flat]"),
      grads_(ctx, layout_.total, "mlp gradients [flat]"),
      kernels_(std::make_unique<ops::MlpKernels>(ctx)) {
  params_.upload(ctx, glorot_uniform_init(config));
  zero_grad();
}

Mlp::~Mlp() = default;

size_t Mlp::bytes_for(const MlpConfig& config) { return 2 * parameter_layout(config).total * sizeof(float); }

std::vector<float> Mlp::download_params() const { return params_.download(*ctx_); }

void Mlp::upload_params(const std::vector<float>& values) {
  if (values.size() != layout_.total) {
    throw Error("MLP: " + std::to_string(values.size()) + " parameter values given, the network (" +
                describe(config_) + ") has " + std::to_string(layout_.total));
  }
  params_.upload(*ctx_, values);
}

std::vector<float> Mlp::download_grads() const { return grads_.download(*ctx_); }

void Mlp::zero_grad() { grads_.fill(*ctx_, 0.0f); }

Workspace Mlp::make_workspace(size_t max_rows, size_t max_rays, WorkspaceMode mode) const {
  return Workspace(*ctx_, config_, max_rows, max_rays, mode);
}

void Mlp::check_inputs(const MlpInputs& in, const Workspace& ws, const char* where) const {
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
}

void Mlp::forward(const MlpInputs& in, const MlpOutputs& out, Workspace& ws) {
  check_inputs(in, ws, "forward");
  const bool save = ws.mode_ == WorkspaceMode::training;
  ws.has_forward_ = false;
  if (ctx_->gemm_on_host()) {
    host_forward(in, out, ws, save);
  } else {
    trunk_forward(in, ws, save);
    heads_forward(in, out, ws, save);
  }
  if (save) {
    ws.inputs_ = in;
    ws.has_forward_ = true;
  }
}

// Layer i: act_i = ReLU(in_i · W_i + b_i), in_0 = features; after a skip point in_i = [act_{i−1} | features],
// done as two products into the same output (the second with beta = 1) instead of copying the concatenation.
void Mlp::trunk_forward(const MlpInputs& in, Workspace& ws, bool save) {
  const size_t rows = in.rows();
  const size_t W = config_.width;
  for (size_t i = 0; i < config_.depth; ++i) {
    const DenseLayer& layer = layout_.trunk[i];
    const std::string name = layer.name + " forward";
    const auto& out_array = ws.activations_[save ? i : i % 2];
    const MatrixView out = view(out_array, W);
    if (i == 0) {
      gemm(*ctx_, gemm_shape(rows, W, config_.input_width), 1.0f, in.features, weights(params_, layer), 0.0f, out, name);
    } else {
      const MatrixView prev = view(ws.activations_[save ? i - 1 : (i - 1) % 2], W);
      gemm(*ctx_, gemm_shape(rows, W, W), 1.0f, prev, weights(params_, layer), 0.0f, out, name);
      if (skip_after(config_, i - 1)) {
        gemm(*ctx_, gemm_shape(rows, W, config_.input_width), 1.0f, in.features, weights(params_, layer, W), 1.0f, out,
             name + " (skip input)");
      }
    }
    kernels_->bias_act_fwd(out, rows, W, params_, layer.bias_offset, true);
  }
}

void Mlp::heads_forward(const MlpInputs& in, const MlpOutputs& out, Workspace& ws, bool save) {
  const size_t rows = in.rows();
  const size_t W = config_.width;
  const size_t last = config_.depth - 1;
  const MatrixView h = view(ws.activations_[save ? last : last % 2], W);

  const DenseLayer& density = layout_.density;
  gemm(*ctx_, gemm_shape(rows, density.out, W), 1.0f, h, weights(params_, density), 0.0f, out.raw_density,
       "density forward");
  kernels_->bias_act_fwd(out.raw_density, rows, density.out, params_, density.bias_offset, false);

  const DenseLayer& rgb = layout_.rgb;
  if (!config_.view_dependence) {
    gemm(*ctx_, gemm_shape(rows, rgb.out, W), 1.0f, h, weights(params_, rgb), 0.0f, out.raw_rgb, "rgb forward");
    kernels_->bias_act_fwd(out.raw_rgb, rows, rgb.out, params_, rgb.bias_offset, false);
    return;
  }
  // Inference reuses the ping-pong buffers: the bottleneck goes to the one h is not in, the view branch
  // back into h's (h is no longer needed once the density and the bottleneck are computed).
  const DenseLayer& bottleneck = layout_.bottleneck;
  const DenseLayer& view_layer = layout_.view;
  const size_t Wb = bottleneck.out, Wv = view_layer.out;
  const MatrixView bneck = save ? view(ws.bottleneck_, Wb) : view(ws.activations_[(last + 1) % 2], Wb);
  const MatrixView hidden = save ? view(ws.view_hidden_, Wv) : view(ws.activations_[last % 2], Wv);
  gemm(*ctx_, gemm_shape(rows, Wb, W), 1.0f, h, weights(params_, bottleneck), 0.0f, bneck, "bottleneck forward");
  kernels_->bias_act_fwd(bneck, rows, Wb, params_, bottleneck.bias_offset, false);
  // View layer: [bottleneck | view_encoding] · W_view = bottleneck · W_view[0:Wb] + (per ray) view · W_view[Wb:].
  gemm(*ctx_, gemm_shape(in.n_rays, Wv, config_.view_width), 1.0f, in.view_encoding, weights(params_, view_layer, Wb),
       0.0f, view(ws.ray_term_, Wv), "view forward (per-ray view encoding)");
  gemm(*ctx_, gemm_shape(rows, Wv, Wb), 1.0f, bneck, weights(params_, view_layer), 0.0f, hidden, "view forward");
  kernels_->bias_ray_relu_fwd(hidden, rows, Wv, params_, view_layer.bias_offset, ws.ray_term_, in.samples_per_ray);
  gemm(*ctx_, gemm_shape(rows, rgb.out, Wv), 1.0f, hidden, weights(params_, rgb), 0.0f, out.raw_rgb, "rgb forward");
  kernels_->bias_act_fwd(out.raw_rgb, rows, rgb.out, params_, rgb.bias_offset, false);
}

void Mlp::backward(Workspace& ws, const MlpOutputGradients& d_out) {
  if (ws.mode_ != WorkspaceMode::training) {
    throw Error("MLP backward: the workspace is an inference workspace (it keeps no activations); make it with "
                "WorkspaceMode::training");
  }
  if (!ws.has_forward_) throw Error("MLP backward: no forward has been run through this workspace");
  check_inputs(ws.inputs_, ws, "backward");
  if (ctx_->gemm_on_host()) {
    host_backward(ws, d_out);
    return;
  }
  if (!ws.device_backward_) {
    throw Error("MLP backward: the workspace was made while gemm_backend=host was in use (it has no device backward "
                "buffers); make workspaces after choosing the backend");
  }
  heads_backward(ws, d_out);
  trunk_backward(ws);
}

// ---- the host path (gemm_backend=host) ----

namespace {

HostMlpOptions default_host_options(const ocl::Context& ctx) {
  HostMlpOptions o;
  o.threads = std::max<size_t>(1, ctx.device_info().compute_units);
  return o;
}

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

void Mlp::set_host_options(const HostMlpOptions& options) { host_ = std::make_unique<HostMlp>(config_, options); }

HostMlpOptions Mlp::host_options() const { return host_ ? host_->options() : default_host_options(*ctx_); }

HostMlp& Mlp::host_mlp() {
  if (!host_) host_ = std::make_unique<HostMlp>(config_, default_host_options(*ctx_));
  return *host_;
}

// What a host forward reads and keeps: the parameters, the inputs and (training) the saved activations. `write`:
// the activations are written (forward) or only read (backward).
void Mlp::need_host_buffers(MappedBuffers& mapped, const MlpInputs& in, const Workspace& ws, bool activations,
                            bool write) const {
  mapped.need(&params_, false);
  mapped.need(in.features, false);
  mapped.need(in.view_encoding, false);
  if (!activations) return;
  for (const auto& a : ws.activations_) mapped.need(&a, write);
  if (config_.view_dependence) {
    mapped.need(&ws.bottleneck_, write);
    mapped.need(&ws.view_hidden_, write);
  }
}

HostForwardBuffers Mlp::host_buffers(const MappedBuffers& mapped, const MlpInputs& in, const Workspace& ws,
                                     bool activations) const {
  HostForwardBuffers b;
  b.params = mapped.at(&params_);
  b.features = mapped.at(in.features);
  b.features_ld = in.features.ld;
  b.view_encoding = config_.view_dependence ? mapped.at(in.view_encoding) : nullptr;
  b.view_ld = in.view_encoding.ld;
  if (activations) {
    for (const auto& a : ws.activations_) b.trunk.push_back(mapped.at(&a));
    if (config_.view_dependence) {
      b.bottleneck = mapped.at(&ws.bottleneck_);
      b.view_hidden = mapped.at(&ws.view_hidden_);
    }
  }
  b.n_rays = in.n_rays;
  b.samples_per_ray = in.samples_per_ray;
  return b;
}

// Maps what the forward reads and writes (blocking: the kernels that wrote the features have finished), runs it on
// the host, and unmaps (the kernels enqueued next see the outputs). See mapped_buffers.hpp.
void Mlp::host_forward(const MlpInputs& in, const MlpOutputs& out, Workspace& ws, bool save) {
  MappedBuffers mapped(*ctx_, "the host MLP's forward");
  need_host_buffers(mapped, in, ws, save, true);
  mapped.need(out.raw_density, true);
  mapped.need(out.raw_rgb, true);
  mapped.map();
  const auto start = std::chrono::steady_clock::now();
  HostForwardBuffers b = host_buffers(mapped, in, ws, save);
  b.density = mapped.at(out.raw_density);
  b.density_ld = out.raw_density.ld;
  b.rgb = mapped.at(out.raw_rgb);
  b.rgb_ld = out.raw_rgb.ld;
  const HostMlpTimes times = host_mlp().forward(b, ctx_->recording_profiler() != nullptr);
  profile_host_call(*ctx_, times, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
}

void Mlp::host_backward(Workspace& ws, const MlpOutputGradients& d_out) {
  MappedBuffers mapped(*ctx_, "the host MLP's backward");
  need_host_buffers(mapped, ws.inputs_, ws, true, false);
  mapped.need(&grads_, true);
  mapped.need(d_out.d_raw_density, false);
  mapped.need(d_out.d_raw_rgb, false);
  mapped.map();
  const auto start = std::chrono::steady_clock::now();
  HostBackwardBuffers b;
  b.saved = host_buffers(mapped, ws.inputs_, ws, true);
  b.d_density = mapped.at(d_out.d_raw_density);
  b.d_density_ld = d_out.d_raw_density.ld;
  b.d_rgb = mapped.at(d_out.d_raw_rgb);
  b.d_rgb_ld = d_out.d_raw_rgb.ld;
  b.grads = mapped.at(&grads_);
  const HostMlpTimes times = host_mlp().backward(b, ctx_->recording_profiler() != nullptr);
  profile_host_call(*ctx_, times, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
}

// grads[bias] += Σ_rows dz (after masking dz by act > 0 when act is given).
void Mlp::bias_gradient(const MatrixView& dz, const MatrixView* act, size_t rows, size_t cols, size_t bias_offset,
                        Workspace& ws) {
  const size_t block = ops::MlpKernels::kRowsPerBlock;
  kernels_->act_bwd_partial(dz, act, rows, cols, block, ws.partials_);
  kernels_->sum_partials(ws.partials_, ops::MlpKernels::blocks_for(rows, block), cols, grads_, bias_offset);
}

// Leaves ∂loss/∂h (h = the trunk's last activation) in grad_a [rows][width].
void Mlp::heads_backward(Workspace& ws, const MlpOutputGradients& d_out) {
  const MlpInputs& in = ws.inputs_;
  const size_t rows = in.rows();
  const size_t W = config_.width;
  const MatrixView h = view(ws.activations_[config_.depth - 1], W);
  const MatrixView dh = view(ws.grad_a_, W);
  const DenseLayer& density = layout_.density;
  const DenseLayer& rgb = layout_.rgb;

  bias_gradient(d_out.d_raw_density, nullptr, rows, density.out, density.bias_offset, ws);
  gemm(*ctx_, gemm_shape(W, density.out, rows, true), 1.0f, h, d_out.d_raw_density, 1.0f, weights(grads_, density),
       "density weight gradient");

  if (!config_.view_dependence) {
    bias_gradient(d_out.d_raw_rgb, nullptr, rows, rgb.out, rgb.bias_offset, ws);
    gemm(*ctx_, gemm_shape(W, rgb.out, rows, true), 1.0f, h, d_out.d_raw_rgb, 1.0f, weights(grads_, rgb),
         "rgb weight gradient");
    gemm(*ctx_, gemm_shape(rows, W, rgb.out, false, true), 1.0f, d_out.d_raw_rgb, weights(params_, rgb), 0.0f, dh,
         "rgb input gradient");
  } else {
    const DenseLayer& bottleneck = layout_.bottleneck;
    const DenseLayer& view_layer = layout_.view;
    const size_t Wb = bottleneck.out, Wv = view_layer.out;
    const MatrixView hidden = view(ws.view_hidden_, Wv);
    const MatrixView bneck = view(ws.bottleneck_, Wb);
    const MatrixView d_hidden = view(ws.grad_a_, Wv);
    const MatrixView d_bneck = view(ws.grad_b_, Wb);

    bias_gradient(d_out.d_raw_rgb, nullptr, rows, rgb.out, rgb.bias_offset, ws);
    gemm(*ctx_, gemm_shape(Wv, rgb.out, rows, true), 1.0f, hidden, d_out.d_raw_rgb, 1.0f, weights(grads_, rgb),
         "rgb weight gradient");
    gemm(*ctx_, gemm_shape(rows, Wv, rgb.out, false, true), 1.0f, d_out.d_raw_rgb, weights(params_, rgb), 0.0f, d_hidden,
         "rgb input gradient");
    // View layer: mask by the ReLU, and sum each ray's samples (its view-encoding rows were shared).
    kernels_->act_bwd_partial(d_hidden, &hidden, rows, Wv, in.samples_per_ray, ws.partials_);
    gemm(*ctx_, gemm_shape(config_.view_width, Wv, in.n_rays, true), 1.0f, in.view_encoding, view(ws.partials_, Wv), 1.0f,
         weights(grads_, view_layer, Wb), "view weight gradient (per-ray view encoding)");
    kernels_->sum_partials(ws.partials_, in.n_rays, Wv, grads_, view_layer.bias_offset);
    gemm(*ctx_, gemm_shape(Wb, Wv, rows, true), 1.0f, bneck, d_hidden, 1.0f, weights(grads_, view_layer),
         "view weight gradient");
    gemm(*ctx_, gemm_shape(rows, Wb, Wv, false, true), 1.0f, d_hidden, weights(params_, view_layer), 0.0f, d_bneck,
         "view input gradient");
    // Bottleneck (no activation).
    bias_gradient(d_bneck, nullptr, rows, Wb, bottleneck.bias_offset, ws);
    gemm(*ctx_, gemm_shape(W, Wb, rows, true), 1.0f, h, d_bneck, 1.0f, weights(grads_, bottleneck),
         "bottleneck weight gradient");
    gemm(*ctx_, gemm_shape(rows, W, Wb, false, true), 1.0f, d_bneck, weights(params_, bottleneck), 0.0f, dh,
         "bottleneck input gradient");
  }
  // h also feeds the density head: its share adds on.
  gemm(*ctx_, gemm_shape(rows, W, density.out, false, true), 1.0f, d_out.d_raw_density, weights(params_, density), 1.0f,
       dh, "density input gradient");
}

void Mlp::trunk_backward(Workspace& ws) {
  const MlpInputs& in = ws.inputs_;
  const size_t rows = in.rows();
  const size_t W = config_.width;
  ocl::DeviceArray<float>* current = &ws.grad_a_;  // holds ∂loss/∂act_i on entry to layer i
  ocl::DeviceArray<float>* other = &ws.grad_b_;
  for (size_t i = config_.depth; i-- > 0;) {
    const DenseLayer& layer = layout_.trunk[i];
    const MatrixView dz = view(*current, W);
    const MatrixView act = view(ws.activations_[i], W);
    bias_gradient(dz, &act, rows, W, layer.bias_offset, ws);  // also turns ∂act into ∂z in place
    const std::string name = layer.name + " weight gradient";
    if (i == 0) {
      gemm(*ctx_, gemm_shape(config_.input_width, W, rows, true), 1.0f, in.features, dz, 1.0f, weights(grads_, layer),
           name);
      break;
    }
    const MatrixView prev = view(ws.activations_[i - 1], W);
    gemm(*ctx_, gemm_shape(W, W, rows, true), 1.0f, prev, dz, 1.0f, weights(grads_, layer), name);
    if (skip_after(config_, i - 1)) {
      gemm(*ctx_, gemm_shape(config_.input_width, W, rows, true), 1.0f, in.features, dz, 1.0f,
           weights(grads_, layer, W), name + " (skip input)");
    }
    // Only the first W input rows of a skip layer come from act_{i−1}; the features need no gradient.
    gemm(*ctx_, gemm_shape(rows, W, W, false, true), 1.0f, dz, weights(params_, layer), 0.0f, view(*other, W),
         layer.name + " input gradient");
    std::swap(current, other);
  }
}

}  // namespace mipnerf::mlp
