// CPU reference of the MLP in double precision.
#include "ref/mlp.hpp"

#include <algorithm>

#include "core/error.hpp"
#include "ref/gemm_ref.hpp"

namespace mipnerf::ref {
namespace {

double relu_keep_nan(double v) { return v < 0.0 ? 0.0 : v; }

// out [rows][layer.out] = act(in [rows][layer.in] · W + b).
std::vector<double> dense_forward(const mlp::DenseLayer& layer, const std::vector<double>& params,
                                  const std::vector<double>& in, size_t rows, bool relu) {
  std::vector<double> out(rows * layer.out);
  gemm<double>(gemm::gemm_shape(rows, layer.out, layer.in), 1.0, in.data(), layer.in, params.data() + layer.weight_offset,
               layer.out, 0.0, out.data(), layer.out);
  mlp_bias_act_fwd(out.data(), 0, layer.out, rows, layer.out, params.data(), layer.bias_offset, relu);
  return out;
}

// Given ∂loss/∂out (masked in place by act > 0 when act is given): grads += ∂loss/∂(W, b); returns ∂loss/∂in.
std::vector<double> dense_backward(const mlp::DenseLayer& layer, const std::vector<double>& params,
                                   const std::vector<double>& in, std::vector<double>& d_out, const double* act,
                                   size_t rows, std::vector<double>& grads) {
  std::vector<double> column_sums(layer.out);
  mlp_act_bwd_partial(d_out.data(), 0, layer.out, act, 0, layer.out, rows, layer.out, std::max<size_t>(rows, 1),
                      act != nullptr, column_sums.data());
  mlp_sum_partials(column_sums.data(), 1, layer.out, grads.data(), layer.bias_offset);
  gemm<double>(gemm::gemm_shape(layer.in, layer.out, rows, true), 1.0, in.data(), layer.in, d_out.data(), layer.out, 1.0,
               grads.data() + layer.weight_offset, layer.out);
  std::vector<double> d_in(rows * layer.in);
  gemm<double>(gemm::gemm_shape(rows, layer.in, layer.out, false, true), 1.0, d_out.data(), layer.out,
               params.data() + layer.weight_offset, layer.out, 0.0, d_in.data(), layer.in);
  return d_in;
}

// [rows][a_cols | b_cols] from two dense matrices.
std::vector<double> concat(const std::vector<double>& a, size_t a_cols, const std::vector<double>& b, size_t b_cols,
                           size_t rows) {
  std::vector<double> out(rows * (a_cols + b_cols));
  for (size_t r = 0; r < rows; ++r) {
    std::copy(a.begin() + r * a_cols, a.begin() + (r + 1) * a_cols, out.begin() + r * (a_cols + b_cols));
    std::copy(b.begin() + r * b_cols, b.begin() + (r + 1) * b_cols, out.begin() + r * (a_cols + b_cols) + a_cols);
  }
  return out;
}

// The first `cols` columns of a [rows][total] matrix.
std::vector<double> left_columns(const std::vector<double>& m, size_t total, size_t cols, size_t rows) {
  std::vector<double> out(rows * cols);
  for (size_t r = 0; r < rows; ++r) std::copy(m.begin() + r * total, m.begin() + r * total + cols, out.begin() + r * cols);
  return out;
}

// acc [rows][cols] += the last `cols` columns of a [rows][total] matrix.
void add_right_columns(const std::vector<double>& m, size_t total, size_t cols, size_t rows, std::vector<double>& acc) {
  for (size_t r = 0; r < rows; ++r) {
    for (size_t c = 0; c < cols; ++c) acc[r * cols + c] += m[r * total + (total - cols) + c];
  }
}

}  // namespace

void mlp_bias_act_fwd(double* z, size_t z_offset, size_t ld, size_t rows, size_t cols, const double* params,
                      size_t bias_offset, bool apply_relu) {
  for (size_t r = 0; r < rows; ++r) {
    for (size_t c = 0; c < cols; ++c) {
      double& v = z[z_offset + r * ld + c];
      v += params[bias_offset + c];
      if (apply_relu) v = relu_keep_nan(v);
    }
  }
}

void mlp_bias_ray_relu_fwd(double* z, size_t z_offset, size_t ld, size_t rows, size_t cols, const double* params,
                           size_t bias_offset, const double* ray_term, size_t samples_per_ray) {
  for (size_t r = 0; r < rows; ++r) {
    const size_t ray = r / samples_per_ray;
    for (size_t c = 0; c < cols; ++c) {
      double& v = z[z_offset + r * ld + c];
      v = relu_keep_nan(v + ray_term[ray * cols + c] + params[bias_offset + c]);
    }
  }
}

void mlp_act_bwd_partial(double* dz, size_t dz_offset, size_t dz_ld, const double* act, size_t act_offset,
                         size_t act_ld, size_t rows, size_t cols, size_t rows_per_block, bool apply_relu,
                         double* partials) {
  const size_t n_blocks = (rows + rows_per_block - 1) / rows_per_block;
  for (size_t b = 0; b < n_blocks; ++b) {
    for (size_t c = 0; c < cols; ++c) {
      double sum = 0.0;
      for (size_t r = b * rows_per_block; r < std::min(rows, (b + 1) * rows_per_block); ++r) {
        double& g = dz[dz_offset + r * dz_ld + c];
        if (apply_relu && !(act[act_offset + r * act_ld + c] > 0.0)) g = 0.0;
        sum += g;
      }
      partials[b * cols + c] = sum;
    }
  }
}

void mlp_sum_partials(const double* partials, size_t n_blocks, size_t cols, double* grad, size_t grad_offset) {
  for (size_t c = 0; c < cols; ++c) {
    double sum = 0.0;
    for (size_t b = 0; b < n_blocks; ++b) sum += partials[b * cols + c];
    grad[grad_offset + c] += sum;
  }
}

void mlp_forward(const mlp::MlpConfig& config, const std::vector<double>& params, const std::vector<double>& features,
                 const std::vector<double>& view_encoding, size_t n_rays, size_t samples_per_ray,
                 std::vector<double>& raw_density, std::vector<double>& raw_rgb, MlpTape* tape) {
  const mlp::ParameterLayout layout = mlp::parameter_layout(config);
  const size_t rows = n_rays * samples_per_ray;
  if (params.size() != layout.total) throw Error("ref::mlp_forward: wrong parameter count");
  if (features.size() < rows * config.input_width) throw Error("ref::mlp_forward: features too small");
  MlpTape local;
  MlpTape& t = tape ? *tape : local;
  t = MlpTape{};
  t.n_rays = n_rays;
  t.samples_per_ray = samples_per_ray;

  std::vector<double> x(features.begin(), features.begin() + rows * config.input_width);
  std::vector<double> in = x;
  for (size_t i = 0; i < config.depth; ++i) {
    std::vector<double> act = dense_forward(layout.trunk[i], params, in, rows, true);
    t.trunk_inputs.push_back(std::move(in));
    in = mlp::skip_after(config, i) ? concat(act, config.width, x, config.input_width, rows) : act;
    t.activations.push_back(std::move(act));
  }
  const std::vector<double>& h = t.activations.back();
  raw_density = dense_forward(layout.density, params, h, rows, false);
  if (!config.view_dependence) {
    raw_rgb = dense_forward(layout.rgb, params, h, rows, false);
    return;
  }
  if (view_encoding.size() < n_rays * config.view_width) throw Error("ref::mlp_forward: view encoding too small");
  t.bottleneck = dense_forward(layout.bottleneck, params, h, rows, false);
  std::vector<double> tiled(rows * config.view_width);
  for (size_t r = 0; r < rows; ++r) {
    const size_t ray = r / samples_per_ray;
    std::copy(view_encoding.begin() + ray * config.view_width, view_encoding.begin() + (ray + 1) * config.view_width,
              tiled.begin() + r * config.view_width);
  }
  t.view_input = concat(t.bottleneck, config.bottleneck_width, tiled, config.view_width, rows);
  t.view_hidden = dense_forward(layout.view, params, t.view_input, rows, true);
  raw_rgb = dense_forward(layout.rgb, params, t.view_hidden, rows, false);
}

void mlp_backward(const mlp::MlpConfig& config, const std::vector<double>& params, const MlpTape& tape,
                  const std::vector<double>& d_raw_density, const std::vector<double>& d_raw_rgb,
                  std::vector<double>& grads, std::vector<double>* d_features) {
  const mlp::ParameterLayout layout = mlp::parameter_layout(config);
  const size_t rows = tape.n_rays * tape.samples_per_ray;
  if (grads.empty()) grads.assign(layout.total, 0.0);
  if (grads.size() != layout.total) throw Error("ref::mlp_backward: wrong gradient count");
  const std::vector<double>& h = tape.activations.back();

  std::vector<double> d_density = d_raw_density;
  std::vector<double> d_rgb = d_raw_rgb;
  std::vector<double> dh = dense_backward(layout.density, params, h, d_density, nullptr, rows, grads);
  std::vector<double> dh_colour;
  if (!config.view_dependence) {
    dh_colour = dense_backward(layout.rgb, params, h, d_rgb, nullptr, rows, grads);
  } else {
    std::vector<double> d_hidden = dense_backward(layout.rgb, params, tape.view_hidden, d_rgb, nullptr, rows, grads);
    std::vector<double> d_view_input =
        dense_backward(layout.view, params, tape.view_input, d_hidden, tape.view_hidden.data(), rows, grads);
    std::vector<double> d_bneck = left_columns(d_view_input, layout.view.in, config.bottleneck_width, rows);
    dh_colour = dense_backward(layout.bottleneck, params, h, d_bneck, nullptr, rows, grads);
  }
  for (size_t i = 0; i < dh.size(); ++i) dh[i] += dh_colour[i];

  // The features feed layer 0 (its whole input) and every skip layer (its input's last input_width columns).
  std::vector<double> d_x(rows * config.input_width, 0.0);
  std::vector<double> d_act = std::move(dh);
  for (size_t i = config.depth; i-- > 0;) {
    const mlp::DenseLayer& layer = layout.trunk[i];
    std::vector<double> d_in =
        dense_backward(layer, params, tape.trunk_inputs[i], d_act, tape.activations[i].data(), rows, grads);
    if (i == 0 || mlp::skip_after(config, i - 1)) add_right_columns(d_in, layer.in, config.input_width, rows, d_x);
    // A skip layer's input is [act_{i−1} | features]: the first `width` columns flow further back.
    if (i > 0) d_act = left_columns(d_in, layer.in, config.width, rows);
  }
  if (d_features != nullptr) *d_features = std::move(d_x);
}

}  // namespace mipnerf::ref
