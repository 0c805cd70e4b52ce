// The device network: every product through CLBlast on the device, bias/activation kernels around them
// (kernels/mlp.cl), and the backward through the workspace's device buffers.
#include "mlp/device_network.hpp"

#include <algorithm>
#include <string>

#include "core/error.hpp"
#include "gemm/gemm.hpp"
#include "gemm/gemm_tuning.hpp"
#include "ops/mlp.hpp"

namespace mipnerf::mlp {
namespace {

// The weights of `layer` from input row `first_row` on: a [rows][out] block of its [in][out] matrix.
MatrixView weights(const ocl::DeviceArray<float>& flat, const DenseLayer& layer, size_t first_row = 0) {
  return view(flat, layer.out, layer.weight_offset + first_row * layer.out);
}

// Partials rows: blocks of kRowsPerBlock rows for bias gradients, or one per ray for the view branch.
size_t partial_rows(const MlpConfig& c, size_t max_rows, size_t max_rays) {
  const size_t blocks = ops::MlpKernels::blocks_for(max_rows, ops::MlpKernels::kRowsPerBlock);
  return c.view_dependence ? std::max(blocks, max_rays) : blocks;
}

size_t partial_cols(const MlpConfig& c) { return std::max({widest_hidden(c), c.density_outputs, c.rgb_outputs}); }

}  // namespace

DeviceWorkspace::DeviceWorkspace(ocl::Context& ctx, const MlpConfig& config, size_t max_rows, size_t max_rays,
                                 WorkspaceMode mode) {
  const size_t max_cols = widest_hidden(config);
  if (mode == WorkspaceMode::training) {
    for (size_t i = 0; i < config.depth; ++i) {
      activations.emplace_back(ctx, max_rows * config.width,
                               "mlp activation of trunk " + std::to_string(i) + " [rows][width]");
    }
    if (config.view_dependence) {
      bottleneck = ocl::DeviceArray<float>(ctx, max_rows * config.bottleneck_width, "mlp bottleneck [rows][width]");
      view_hidden = ocl::DeviceArray<float>(ctx, max_rows * config.view_branch_width,
                                            "mlp view-branch activation [rows][view_branch_width]");
    }
    grad_a = ocl::DeviceArray<float>(ctx, max_rows * max_cols, "mlp backward buffer A [rows][width]");
    grad_b = ocl::DeviceArray<float>(ctx, max_rows * max_cols, "mlp backward buffer B [rows][width]");
    partials = ocl::DeviceArray<float>(ctx, partial_rows(config, max_rows, max_rays) * partial_cols(config),
                                       "mlp column-sum partials [blocks][width]");
  } else {
    for (int i = 0; i < 2; ++i) {
      activations.emplace_back(ctx, max_rows * max_cols,
                               "mlp inference buffer " + std::to_string(i) + " [rows][width]");
    }
  }
  if (config.view_dependence) {
    ray_term = ocl::DeviceArray<float>(ctx, max_rays * config.view_branch_width,
                                       "mlp per-ray view product [rays][view_branch_width]");
  }
}

size_t DeviceWorkspace::bytes_for(const MlpConfig& c, size_t max_rows, size_t max_rays, WorkspaceMode mode) {
  const size_t cols = widest_hidden(c);
  size_t floats = c.view_dependence ? max_rays * c.view_branch_width : 0;
  if (mode == WorkspaceMode::training) {
    floats +=
        c.depth * max_rows * c.width + 2 * max_rows * cols + partial_rows(c, max_rows, max_rays) * partial_cols(c);
    if (c.view_dependence) floats += max_rows * (c.bottleneck_width + c.view_branch_width);
  } else {
    floats += 2 * max_rows * cols;
  }
  return floats * sizeof(float);
}

DeviceNetwork::DeviceNetwork(ocl::Context& ctx, const MlpConfig& config)
    : Network(ctx, config), kernels_(std::make_unique<ops::MlpKernels>(ctx)) {
  gemm::prepare_clblast_tuning(ctx);  // this device's tuned parameters, before the first product
}

DeviceNetwork::~DeviceNetwork() = default;

std::unique_ptr<WorkspaceBuffers> DeviceNetwork::make_workspace_buffers(size_t max_rows, size_t max_rays,
                                                                        WorkspaceMode mode) const {
  return std::make_unique<DeviceWorkspace>(*ctx_, config_, max_rows, max_rays, mode);
}

void DeviceNetwork::forward_impl(const MlpInputs& in, const MlpOutputs& out, Workspace& ws, bool save) {
  DeviceWorkspace& buffers = ws.buffers<DeviceWorkspace>("forward");
  trunk_forward(in, buffers, save);
  heads_forward(in, out, buffers, save);
}

void DeviceNetwork::backward_impl(const MlpInputs& in, Workspace& ws, const MlpOutputGradients& d_out,
                                  const MatrixView& d_features) {
  DeviceWorkspace& buffers = ws.buffers<DeviceWorkspace>("backward");
  heads_backward(in, buffers, d_out);
  trunk_backward(in, buffers, d_features);
}

// Layer i: act_i = ReLU(in_i · W_i + b_i), in_0 = features; after a skip point in_i = [act_{i−1} | features],
// done as two products into the same output (the second with beta = 1) instead of copying the concatenation.
void DeviceNetwork::trunk_forward(const MlpInputs& in, DeviceWorkspace& ws, bool save) {
  const size_t rows = in.rows();
  const size_t W = config_.width;
  for (size_t i = 0; i < config_.depth; ++i) {
    const DenseLayer& layer = layout_.trunk[i];
    const std::string name = layer.name + " forward";
    const auto& out_array = ws.activations[save ? i : i % 2];
    const MatrixView out = view(out_array, W);
    if (i == 0) {
      gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, W, config_.input_width), 1.0f, in.features,
                  weights(params_, layer), 0.0f, out, name);
    } else {
      const MatrixView prev = view(ws.activations[save ? i - 1 : (i - 1) % 2], W);
      gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, W, W), 1.0f, prev, weights(params_, layer),
                  0.0f, out, name);
      if (skip_after(config_, i - 1)) {
        gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, W, config_.input_width), 1.0f,
                    in.features, weights(params_, layer, W), 1.0f, out, name + " (skip input)");
      }
    }
    kernels_->bias_act_fwd(out, rows, W, params_, layer.bias_offset, true);
  }
}

void DeviceNetwork::heads_forward(const MlpInputs& in, const MlpOutputs& out, DeviceWorkspace& ws, bool save) {
  const size_t rows = in.rows();
  const size_t W = config_.width;
  const size_t last = config_.depth - 1;
  const MatrixView h = view(ws.activations[save ? last : last % 2], W);

  const DenseLayer& density = layout_.density;
  gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, density.out, W), 1.0f, h,
              weights(params_, density), 0.0f, out.raw_density, "density forward");
  kernels_->bias_act_fwd(out.raw_density, rows, density.out, params_, density.bias_offset, false);
  if (out.raw_rgb.array == nullptr) return;  // density only (inference of a level whose colour nothing reads)

  const DenseLayer& rgb = layout_.rgb;
  if (!config_.view_dependence) {
    gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, rgb.out, W), 1.0f, h, weights(params_, rgb),
                0.0f, out.raw_rgb, "rgb forward");
    kernels_->bias_act_fwd(out.raw_rgb, rows, rgb.out, params_, rgb.bias_offset, false);
    return;
  }
  // Inference reuses the ping-pong buffers: the bottleneck goes to the one h is not in, the view branch
  // back into h's (h is no longer needed once the density and the bottleneck are computed).
  const DenseLayer& bottleneck = layout_.bottleneck;
  const DenseLayer& view_layer = layout_.view;
  const size_t Wb = bottleneck.out, Wv = view_layer.out;
  const MatrixView bneck = save ? view(ws.bottleneck, Wb) : view(ws.activations[(last + 1) % 2], Wb);
  const MatrixView hidden = save ? view(ws.view_hidden, Wv) : view(ws.activations[last % 2], Wv);
  gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, Wb, W), 1.0f, h, weights(params_, bottleneck),
              0.0f, bneck, "bottleneck forward");
  kernels_->bias_act_fwd(bneck, rows, Wb, params_, bottleneck.bias_offset, false);
  // View layer: [bottleneck | view_encoding] · W_view = bottleneck · W_view[0:Wb] + (per ray) view · W_view[Wb:].
  gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(in.n_rays, Wv, config_.view_width), 1.0f,
              in.view_encoding, weights(params_, view_layer, Wb), 0.0f, view(ws.ray_term, Wv),
              "view forward (per-ray view encoding)");
  gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, Wv, Wb), 1.0f, bneck,
              weights(params_, view_layer), 0.0f, hidden, "view forward");
  kernels_->bias_ray_relu_fwd(hidden, rows, Wv, params_, view_layer.bias_offset, ws.ray_term, in.samples_per_ray);
  gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, rgb.out, Wv), 1.0f, hidden,
              weights(params_, rgb), 0.0f, out.raw_rgb, "rgb forward");
  kernels_->bias_act_fwd(out.raw_rgb, rows, rgb.out, params_, rgb.bias_offset, false);
}

// grads[bias] += Σ_rows dz (after masking dz by act > 0 when act is given).
void DeviceNetwork::bias_gradient(const MatrixView& dz, const MatrixView* act, size_t rows, size_t cols,
                                  size_t bias_offset, DeviceWorkspace& ws) {
  const size_t block = ops::MlpKernels::kRowsPerBlock;
  kernels_->act_bwd_partial(dz, act, rows, cols, block, ws.partials);
  kernels_->sum_partials(ws.partials, ops::MlpKernels::blocks_for(rows, block), cols, grads_, bias_offset);
}

// Leaves ∂loss/∂h (h = the trunk's last activation) in grad_a [rows][width].
void DeviceNetwork::heads_backward(const MlpInputs& in, DeviceWorkspace& ws, const MlpOutputGradients& d_out) {
  const size_t rows = in.rows();
  const size_t W = config_.width;
  const MatrixView h = view(ws.activations[config_.depth - 1], W);
  const MatrixView dh = view(ws.grad_a, W);
  const DenseLayer& density = layout_.density;
  const DenseLayer& rgb = layout_.rgb;

  bias_gradient(d_out.d_raw_density, nullptr, rows, density.out, density.bias_offset, ws);
  gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(W, density.out, rows, true), 1.0f, h,
              d_out.d_raw_density, 1.0f, weights(grads_, density), "density weight gradient");

  if (!config_.view_dependence) {
    bias_gradient(d_out.d_raw_rgb, nullptr, rows, rgb.out, rgb.bias_offset, ws);
    gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(W, rgb.out, rows, true), 1.0f, h, d_out.d_raw_rgb,
                1.0f, weights(grads_, rgb), "rgb weight gradient");
    gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, W, rgb.out, false, true), 1.0f,
                d_out.d_raw_rgb, weights(params_, rgb), 0.0f, dh, "rgb input gradient");
  } else {
    const DenseLayer& bottleneck = layout_.bottleneck;
    const DenseLayer& view_layer = layout_.view;
    const size_t Wb = bottleneck.out, Wv = view_layer.out;
    const MatrixView hidden = view(ws.view_hidden, Wv);
    const MatrixView bneck = view(ws.bottleneck, Wb);
    const MatrixView d_hidden = view(ws.grad_a, Wv);
    const MatrixView d_bneck = view(ws.grad_b, Wb);

    bias_gradient(d_out.d_raw_rgb, nullptr, rows, rgb.out, rgb.bias_offset, ws);
    gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(Wv, rgb.out, rows, true), 1.0f, hidden,
                d_out.d_raw_rgb, 1.0f, weights(grads_, rgb), "rgb weight gradient");
    gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, Wv, rgb.out, false, true), 1.0f,
                d_out.d_raw_rgb, weights(params_, rgb), 0.0f, d_hidden, "rgb input gradient");
    // View layer: mask by the ReLU, and sum each ray's samples (its view-encoding rows were shared).
    kernels_->act_bwd_partial(d_hidden, &hidden, rows, Wv, in.samples_per_ray, ws.partials);
    gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(config_.view_width, Wv, in.n_rays, true), 1.0f,
                in.view_encoding, view(ws.partials, Wv), 1.0f, weights(grads_, view_layer, Wb),
                "view weight gradient (per-ray view encoding)");
    kernels_->sum_partials(ws.partials, in.n_rays, Wv, grads_, view_layer.bias_offset);
    gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(Wb, Wv, rows, true), 1.0f, bneck, d_hidden, 1.0f,
                weights(grads_, view_layer), "view weight gradient");
    gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, Wb, Wv, false, true), 1.0f, d_hidden,
                weights(params_, view_layer), 0.0f, d_bneck, "view input gradient");
    // Bottleneck (no activation).
    bias_gradient(d_bneck, nullptr, rows, Wb, bottleneck.bias_offset, ws);
    gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(W, Wb, rows, true), 1.0f, h, d_bneck, 1.0f,
                weights(grads_, bottleneck), "bottleneck weight gradient");
    gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, W, Wb, false, true), 1.0f, d_bneck,
                weights(params_, bottleneck), 0.0f, dh, "bottleneck input gradient");
  }
  // h also feeds the density head: its share adds on.
  gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, W, density.out, false, true), 1.0f,
              d_out.d_raw_density, weights(params_, density), 1.0f, dh, "density input gradient");
}

// d_features [rows][input_width] (=, or += once `written`) dz · W_layer[first_row : first_row + input_width]ᵀ: the
// gradient through the input rows of `layer` that take the features. The first call overwrites (the caller's buffer
// holds anything), the later ones add on.
void DeviceNetwork::features_gradient(const MatrixView& dz, const DenseLayer& layer, size_t first_row, size_t rows,
                                      const MatrixView& d_features, bool& written) {
  gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, config_.input_width, layer.out, false, true),
              1.0f, dz, weights(params_, layer, first_row), written ? 1.0f : 0.0f, d_features,
              layer.name + " features gradient");
  written = true;
}

// d_features (array null: not asked for) gets ∂loss/∂features: the deepest skip layer's share first, layer 0's last.
void DeviceNetwork::trunk_backward(const MlpInputs& in, DeviceWorkspace& ws, const MatrixView& d_features) {
  const bool want_features = d_features.array != nullptr;
  bool features_written = false;
  const size_t rows = in.rows();
  const size_t W = config_.width;
  ocl::DeviceArray<float>* current = &ws.grad_a;  // holds ∂loss/∂act_i on entry to layer i
  ocl::DeviceArray<float>* other = &ws.grad_b;
  for (size_t i = config_.depth; i-- > 0;) {
    const DenseLayer& layer = layout_.trunk[i];
    const MatrixView dz = view(*current, W);
    const MatrixView act = view(ws.activations[i], W);
    bias_gradient(dz, &act, rows, W, layer.bias_offset, ws);  // also turns ∂act into ∂z in place
    const std::string name = layer.name + " weight gradient";
    if (i == 0) {
      gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(config_.input_width, W, rows, true), 1.0f,
                  in.features, dz, 1.0f, weights(grads_, layer), name);
      if (want_features) features_gradient(dz, layer, 0, rows, d_features, features_written);
      break;
    }
    const MatrixView prev = view(ws.activations[i - 1], W);
    gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(W, W, rows, true), 1.0f, prev, dz, 1.0f,
                weights(grads_, layer), name);
    if (skip_after(config_, i - 1)) {
      gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(config_.input_width, W, rows, true), 1.0f,
                  in.features, dz, 1.0f, weights(grads_, layer, W), name + " (skip input)");
      if (want_features) features_gradient(dz, layer, W, rows, d_features, features_written);
    }
    // The first W input rows of a skip layer come from act_{i−1}, the rest from the features (above).
    gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, W, W, false, true), 1.0f, dz,
                weights(params_, layer), 0.0f, view(*other, W), layer.name + " input gradient");
    std::swap(current, other);
  }
}

}  // namespace mipnerf::mlp
