// Helpers of the tests/official model tests (test_model.cpp, test_train_step.cpp): the official model's configuration
// as ours, its weights in our flat parameter buffer, the batch of Multicam pixels the fixtures use, our graph run on
// it, and the bound of a model output derived from the official model's per-stage sensitivities (model_vectors.py).
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "data/dataset.hpp"
#include "data/device_dataset.hpp"
#include "graph/graph.hpp"
#include "mlp/mlp_config.hpp"
#include "mlp/network.hpp"
#include "official_fixtures.hpp"
#include "official_scenes.hpp"
#include "support/data_fixtures.hpp"
#include "support/test_context.hpp"
#include "train/config.hpp"
#include "train/model.hpp"

namespace mipnerf::official {

inline std::string setting_text(const io::Json& value) {
  if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
  if (value.is_string()) return value.get<std::string>();
  std::ostringstream out;
  out.precision(17);
  out << value.get<double>();
  return out.str();
}

// Our configuration of the fixture's MipNerfModel and MLP fields (models.py names → our settings), white background
// (the multiscale Blender default), sampling randomized or not, and `overrides` last.
inline train::TrainConfig model_config(const io::Json& fx, bool randomized, const train::Bundle& overrides = {}) {
  const auto& m = fx.at("model");
  const auto& mlp = fx.at("mlp");
  REQUIRE(m.at("use_viewdirs").get<bool>());
  REQUIRE_FALSE(m.at("disable_integration").get<bool>());
  REQUIRE(mlp.at("net_depth_condition").get<int>() == 1);  // ours: one view-branch layer, as the paper's
  train::Bundle settings = {{"num_samples", setting_text(m.at("num_samples"))},
                            {"num_levels", setting_text(m.at("num_levels"))},
                            {"resample_padding", setting_text(m.at("resample_padding"))},
                            {"lindisp", setting_text(m.at("lindisp"))},
                            {"ray_shape", setting_text(m.at("ray_shape"))},
                            {"pos_min_deg", setting_text(m.at("min_deg_point"))},
                            {"pos_max_deg", setting_text(m.at("max_deg_point"))},
                            {"view_max_deg", setting_text(m.at("deg_view"))},
                            {"density_bias", setting_text(m.at("density_bias"))},
                            {"rgb_padding", setting_text(m.at("rgb_padding"))},
                            {"density_noise", setting_text(m.value("density_noise", io::Json(0.0)))},
                            {"mlp_depth", setting_text(mlp.at("net_depth"))},
                            {"mlp_width", setting_text(mlp.at("net_width"))},
                            {"mlp_skip", setting_text(mlp.at("skip_layer"))},
                            {"view_branch_width", setting_text(mlp.at("net_width_condition"))},
                            {"randomized", randomized ? "true" : "false"},
                            {"background", "white"}};
  for (const auto& [name, value] : overrides) settings[name] = value;
  return train::resolve_config("paper", "mipnerf", settings);
}

// The fixture's Dense layers (flax MLP_0/Dense_0 … in creation order: trunk, density, bottleneck, view, rgb) in our
// flat buffer (host/mlp/mlp_config.hpp: the same order, weights [in][out] row-major then biases). Every shape is
// checked against our layout. `swap_rows` (mutations): layers whose input rows are a concatenation [a | b] get the
// blocks swapped, as if one side concatenated [b | a]: "skip" (trunk layer after the skip: [activation | features]),
// "view" ([bottleneck | view encoding]).
inline std::vector<float> model_params(const io::Json& fx, const mlp::MlpConfig& config,
                                       const std::string& swap_rows = "") {
  const auto layout = mlp::parameter_layout(config);
  const auto layers = layout.all();
  const auto& dense = fx.at("params");
  REQUIRE(dense.size() == layers.size());
  std::vector<float> params(layout.total);
  for (size_t k = 0; k < layers.size(); ++k) {
    const auto& layer = *layers[k];
    CAPTURE(layer.name);
    REQUIRE(dense.at(k).at("name").get<std::string>() == "Dense_" + std::to_string(k));
    const auto kernel = flat(dense.at(k).at("kernel"), {layer.in, layer.out});
    const auto bias = flat(dense.at(k).at("bias"), {layer.out});
    size_t first_block = 0;  // rows of the first concatenated part, when swapping
    if (swap_rows == "skip" && k > 0 && k < config.depth && mlp::skip_after(config, k - 1)) first_block = config.width;
    if (swap_rows == "view" && layer.name == "view") first_block = config.bottleneck_width;
    for (size_t row = 0; row < layer.in; ++row) {
      const size_t from = first_block ? (row + first_block) % layer.in : row;
      for (size_t col = 0; col < layer.out; ++col) {
        params[layer.weight_offset + row * layer.out + col] = static_cast<float>(kernel[from * layer.out + col]);
      }
    }
    for (size_t col = 0; col < layer.out; ++col) params[layer.bias_offset + col] = static_cast<float>(bias[col]);
  }
  return params;
}

// The batch of the model fixtures: multicam.json's scene on disk, loaded by our loader, and the fixture's pixels
// (indices in the official all_images order) as our cameras and pixel ids.
struct ModelBatch {
  test::TempDir dir;
  data::Dataset dataset;
  std::unique_ptr<data::DeviceDataset> device_data;
  std::vector<uint32_t> camera_ids, pixel_ids;
  std::vector<float> target_rgb, lossmult;  // [R][3], [R]: our loader's pixels and lossmult at those rays
  size_t n_rays = 0;
  std::unique_ptr<ocl::DeviceArray<uint32_t>> camera_ids_dev, pixel_ids_dev;
  std::unique_ptr<ocl::DeviceArray<float>> target_dev, lossmult_dev;

  explicit ModelBatch(const io::Json& fx) {
    auto& ctx = test::test_context();
    write_multicam_scene(fixture("multicam.json").at("inputs"), dir.path());
    data::LoadOptions options;
    options.splits = {"train"};
    dataset = data::load_dataset(dir.path(), options);
    const auto& split = dataset.split("train");
    for (const auto& index : fx.at("rays").at("multicam_pixels")) {
      const uint64_t i = index.get<uint64_t>();
      size_t c = 0;
      while (split.pixel_offsets[c + 1] <= i) ++c;
      camera_ids.push_back(static_cast<uint32_t>(c));
      pixel_ids.push_back(static_cast<uint32_t>(i - split.pixel_offsets[c]));
      for (int k = 0; k < 3; ++k) target_rgb.push_back(split.rgb[3 * i + k]);
      lossmult.push_back(static_cast<float>(split.cameras[c].lossmult));
    }
    n_rays = camera_ids.size();
    device_data = std::make_unique<data::DeviceDataset>(ctx, split);
    camera_ids_dev = std::make_unique<ocl::DeviceArray<uint32_t>>(upload(ctx, camera_ids, "camera_ids [R]"));
    pixel_ids_dev = std::make_unique<ocl::DeviceArray<uint32_t>>(upload(ctx, pixel_ids, "pixel_ids [R]"));
    target_dev = std::make_unique<ocl::DeviceArray<float>>(upload(ctx, target_rgb, "target_rgb [R][3]"));
    lossmult_dev = std::make_unique<ocl::DeviceArray<float>>(upload(ctx, lossmult, "lossmult [R]"));
  }
  graph::RaySource source() const { return {device_data->cameras(), *camera_ids_dev, *pixel_ids_dev}; }
  double lossmult_sum() const {
    double sum = 0;
    for (float m : lossmult) sum += m;
    return sum;
  }
};

// Our outputs of every level, [level][ray][comp_rgb 0..2, acc, distance] (the fixtures' output_layout).
inline std::vector<float> level_outputs(const graph::Graph& graph, size_t n_levels, size_t n_rays) {
  auto& ctx = test::test_context();
  std::vector<float> out(n_levels * n_rays * 5);
  for (size_t l = 0; l < n_levels; ++l) {
    const auto& level = graph.level_outputs(l);
    const auto comp = level.comp_rgb.download(ctx), acc = level.acc.download(ctx), dist = level.distance.download(ctx);
    for (size_t r = 0; r < n_rays; ++r) {
      float* o = &out[(l * n_rays + r) * 5];
      for (int k = 0; k < 3; ++k) o[k] = comp[3 * r + k];
      o[3] = acc[r];
      o[4] = dist[r];
    }
  }
  return out;
}

// The bound of every model output [level][ray][5], from the official model's first-order sensitivities S_s (the
// fixture's "sensitivities": an error of c_s·u·m_i in every value i of stage s moves an output by at most c_s·u·S_s,
// m_i the magnitude that stage's bound multiplies; model_vectors.py) and our float32 error c_s of each stage, from the
// stage tests against the official outputs:
//   directions 16 (×‖d‖₁, test_datasets/test_multicam), radii 8 (× r·(1 + ‖d‖·f)), unit view directions 16
//   (× ‖d‖₁/‖d‖ + ½, i.e. 16u·‖d‖₁/‖d‖ + 8u), edges 16 (× |t|: stratified 16u·|t|, resampled 4u·|t| — test_ray_math),
//   resampling (4N + 8) (× the widest bin / p_min, N the coarse level's intervals), Gaussian means 16
//   (× |o| + |t_mean·d|) and covariances 64 (× t_var·d² + r_var), IPE 16 (× the feature's envelope e_l: the fused
//   kernel's 16u·e_l given exact moments), view PE 8 (× 1), each dense layer n_in + 2 (× |x|·|W| + |b|: a dot product
//   of n_in terms in any order plus the bias), density 16 (× softplus(x) + |x|·sigmoid(x): softplus' own 12u·y and the
//   roundings of raw + noise and of + bias, ≤ u·(2|x| + 1)·sigmoid ≤ 4u·y + 2u·|x|·sigmoid), colour 16 (× 1: the
//   widened sigmoid ≤ 16u), the coarse weights (N + 16) (× (1 + τ_{i+1})·w_i: the volume rendering bound, felt by the
//   fine level through resampling) and the density noise's draws 36 (× |z|: the kernel's float32 normal against
//   rng_normal4, tests/ops).
// Plus each level's own rendering (the render.json bound, W = Σ_i (1 + τ_{i+1})·w_i from the fixture):
// acc (N + 16)u·W + N·u·acc, comp (2 with white)·(N + 16)u·W + 2N·u, distance (2(N + 16)u·W/acc + 2N·u)·|distance|.
// First order only: the second-order terms are O(u²) of the same sensitivities.
inline std::vector<double> model_output_bounds(const io::Json& fx, const mlp::MlpConfig& mlp_config) {
  const auto& sens = fx.at("sensitivities");
  const auto values = flat(fx.at("outputs"));
  const size_t n_levels = fx.at("outputs").size(), n_rays = fx.at("outputs").at(0).size();
  const double n = fx.at("model").at("num_samples").get<double>();
  const auto layout = mlp::parameter_layout(mlp_config);
  const auto layers = layout.all();
  std::vector<std::pair<std::string, double>> constants = {{"directions", 16},
                                                           {"radii", 8},
                                                           {"viewdirs", 16},
                                                           {"t", 16},
                                                           {"resample", 4 * n + 8},
                                                           {"means", 16},
                                                           {"covs", 64},
                                                           {"ipe", 16},
                                                           {"pe", 8},
                                                           {"density", 16},
                                                           {"rgb", 16},
                                                           {"coarse_weights", n + 16},
                                                           {"noise", 36}};
  for (size_t k = 0; k < layers.size(); ++k) {
    constants.push_back({"dense/Dense_" + std::to_string(k), static_cast<double>(layers[k]->in) + 2});
  }
  std::vector<double> bound(n_levels * n_rays * 5, 0.0);
  size_t used = 0;
  for (const auto& [stage, c] : constants) {
    if (!sens.contains(stage)) continue;
    ++used;
    const auto s = flat(sens.at(stage), {n_levels, n_rays, 5});
    for (size_t i = 0; i < bound.size(); ++i) bound[i] += c * kU * s[i];
  }
  // Every stage the fixture measured has its constant here (a stage without one would go unbounded).
  REQUIRE(used + 1 == sens.size());
  const auto weight_sums = flat(sens.at("render_weight_sums"), {n_levels, n_rays});
  for (size_t l = 0; l < n_levels; ++l) {
    for (size_t r = 0; r < n_rays; ++r) {
      double* b = &bound[(l * n_rays + r) * 5];
      const double* v = &values[(l * n_rays + r) * 5];
      const double w = (n + 16) * kU * weight_sums[l * n_rays + r];
      for (int k = 0; k < 3; ++k) b[k] += 2 * w + 2 * n * kU;
      b[3] += w + n * kU * v[3];
      b[4] += (2 * w / v[3] + 2 * n * kU) * std::abs(v[4]);
    }
  }
  return bound;
}

}  // namespace mipnerf::official
