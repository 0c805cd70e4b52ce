// The device network: every product through CLBlast on the device, bias/activation kernels around them
// (kernels/mlp.cl), and the backward through the workspace's device buffers.
#include "mlp/device_network.hpp"

#include <string>

#include "core/error.hpp"
#include "gemm/gemm.hpp"
#include "ops/mlp.hpp"

namespace mipnerf::mlp {
namespace {

// The weights of `layer` from input row `first_row` on: a [rows][out] block of its [in][out] matrix.
MatrixView weights(const ocl::DeviceArray<float>& flat, const DenseLayer& layer, size_t first_row = 0) {
  return view(flat, layer.out, layer.weight_offset + first_row * layer.out);
}

}  // namespace

DeviceNetwork::DeviceNetwork(ocl::Context& ctx, const MlpConfig& config)
    : Network(ctx, config), kernels_(std::make_unique<ops::MlpKernels>(ctx)) {}

DeviceNetwork::~DeviceNetwork() = default;

void DeviceNetwork::forward_impl(const MlpInputs& in, const MlpOutputs& out, Workspace& ws, bool save) {
  trunk_forward(in, ws, save);
  heads_forward(in, out, ws, save);
}

void DeviceNetwork::backward_impl(Workspace& ws, const MlpOutputGradients& d_out) {
  heads_backward(ws, d_out);
  trunk_backward(ws);
}

// Layer i: act_i = ReLU(in_i · W_i + b_i), in_0 = features; after a skip point in_i = [act_{i−1} | features],
// done as two products into the same output (the second with beta = 1) instead of copying the concatenation.
void DeviceNetwork::trunk_forward(const MlpInputs& in, Workspace& ws, bool save) {
  const size_t rows = in.rows();
  const size_t W = config_.width;
  for (size_t i = 0; i < config_.depth; ++i) {
    const DenseLayer& layer = layout_.trunk[i];
    const std::string name = layer.name + " forward";
    const auto& out_array = ws.activations_[save ? i : i % 2];
    const MatrixView out = view(out_array, W);
    if (i == 0) {
      gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, W, config_.input_width), 1.0f, in.features,
                  weights(params_, layer), 0.0f, out, name);
    } else {
      const MatrixView prev = view(ws.activations_[save ? i - 1 : (i - 1) % 2], W);
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

void DeviceNetwork::heads_forward(const MlpInputs& in, const MlpOutputs& out, Workspace& ws, bool save) {
  const size_t rows = in.rows();
  const size_t W = config_.width;
  const size_t last = config_.depth - 1;
  const MatrixView h = view(ws.activations_[save ? last : last % 2], W);

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
  const MatrixView bneck = save ? view(ws.bottleneck_, Wb) : view(ws.activations_[(last + 1) % 2], Wb);
  const MatrixView hidden = save ? view(ws.view_hidden_, Wv) : view(ws.activations_[last % 2], Wv);
  gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, Wb, W), 1.0f, h, weights(params_, bottleneck),
              0.0f, bneck, "bottleneck forward");
  kernels_->bias_act_fwd(bneck, rows, Wb, params_, bottleneck.bias_offset, false);
  // View layer: [bottleneck | view_encoding] · W_view = bottleneck · W_view[0:Wb] + (per ray) view · W_view[Wb:].
  gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(in.n_rays, Wv, config_.view_width), 1.0f,
              in.view_encoding, weights(params_, view_layer, Wb), 0.0f, view(ws.ray_term_, Wv),
              "view forward (per-ray view encoding)");
  gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, Wv, Wb), 1.0f, bneck,
              weights(params_, view_layer), 0.0f, hidden, "view forward");
  kernels_->bias_ray_relu_fwd(hidden, rows, Wv, params_, view_layer.bias_offset, ws.ray_term_, in.samples_per_ray);
  gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, rgb.out, Wv), 1.0f, hidden,
              weights(params_, rgb), 0.0f, out.raw_rgb, "rgb forward");
  kernels_->bias_act_fwd(out.raw_rgb, rows, rgb.out, params_, rgb.bias_offset, false);
}

// grads[bias] += Σ_rows dz (after masking dz by act > 0 when act is given).
void DeviceNetwork::bias_gradient(const MatrixView& dz, const MatrixView* act, size_t rows, size_t cols,
                                  size_t bias_offset, Workspace& ws) {
  const size_t block = ops::MlpKernels::kRowsPerBlock;
  kernels_->act_bwd_partial(dz, act, rows, cols, block, ws.partials_);
  kernels_->sum_partials(ws.partials_, ops::MlpKernels::blocks_for(rows, block), cols, grads_, bias_offset);
}

// Leaves ∂loss/∂h (h = the trunk's last activation) in grad_a [rows][width].
void DeviceNetwork::heads_backward(Workspace& ws, const MlpOutputGradients& d_out) {
  const MlpInputs& in = ws.inputs_;
  const size_t rows = in.rows();
  const size_t W = config_.width;
  const MatrixView h = view(ws.activations_[config_.depth - 1], W);
  const MatrixView dh = view(ws.grad_a_, W);
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
    const MatrixView hidden = view(ws.view_hidden_, Wv);
    const MatrixView bneck = view(ws.bottleneck_, Wb);
    const MatrixView d_hidden = view(ws.grad_a_, Wv);
    const MatrixView d_bneck = view(ws.grad_b_, Wb);

    bias_gradient(d_out.d_raw_rgb, nullptr, rows, rgb.out, rgb.bias_offset, ws);
    gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(Wv, rgb.out, rows, true), 1.0f, hidden,
                d_out.d_raw_rgb, 1.0f, weights(grads_, rgb), "rgb weight gradient");
    gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, Wv, rgb.out, false, true), 1.0f,
                d_out.d_raw_rgb, weights(params_, rgb), 0.0f, d_hidden, "rgb input gradient");
    // View layer: mask by the ReLU, and sum each ray's samples (its view-encoding rows were shared).
    kernels_->act_bwd_partial(d_hidden, &hidden, rows, Wv, in.samples_per_ray, ws.partials_);
    gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(config_.view_width, Wv, in.n_rays, true), 1.0f,
                in.view_encoding, view(ws.partials_, Wv), 1.0f, weights(grads_, view_layer, Wb),
                "view weight gradient (per-ray view encoding)");
    kernels_->sum_partials(ws.partials_, in.n_rays, Wv, grads_, view_layer.bias_offset);
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

void DeviceNetwork::trunk_backward(Workspace& ws) {
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
      gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(config_.input_width, W, rows, true), 1.0f,
                  in.features, dz, 1.0f, weights(grads_, layer), name);
      break;
    }
    const MatrixView prev = view(ws.activations_[i - 1], W);
    gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(W, W, rows, true), 1.0f, prev, dz, 1.0f,
                weights(grads_, layer), name);
    if (skip_after(config_, i - 1)) {
      gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(config_.input_width, W, rows, true), 1.0f,
                  in.features, dz, 1.0f, weights(grads_, layer, W), name + " (skip input)");
    }
    // Only the first W input rows of a skip layer come from act_{i−1}; the features need no gradient.
    gemm::sgemm(*ctx_, gemm::GemmBackend::clblast, gemm::gemm_shape(rows, W, W, false, true), 1.0f, dz,
                weights(params_, layer), 0.0f, view(*other, W), layer.name + " input gradient");
    std::swap(current, other);
  }
}

}  // namespace mipnerf::mlp
