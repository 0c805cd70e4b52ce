// MLP configuration checks, parameter layout and initialisation.
#include "mlp/mlp_config.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/error.hpp"
#include "core/rng.hpp"

namespace mipnerf::mlp {
namespace {

// Philox stream of the weight initialisation: far from the kernels' RNG_STREAM_* values (0…3), so the
// initial weights never share numbers with sampling.
constexpr uint32_t kInitStream = 0x6D6C7049u;  // "mlpI"

void require_positive(size_t value, const char* field) {
  if (value == 0) throw Error(std::string("MLP configuration: ") + field + " must be positive");
}

DenseLayer make_layer(std::string name, size_t in, size_t out, size_t& offset) {
  DenseLayer layer{std::move(name), in, out, offset, offset + in * out};
  offset += layer.parameter_count();
  return layer;
}

}  // namespace

void MlpConfig::validate() const {
  require_positive(input_width, "input_width");
  require_positive(depth, "depth");
  require_positive(width, "width");
  require_positive(density_outputs, "density_outputs");
  require_positive(rgb_outputs, "rgb_outputs");
  if (view_dependence) {
    require_positive(view_width, "view_width");
    require_positive(view_branch_width, "view_branch_width");
    require_positive(bottleneck_width, "bottleneck_width");
  }
  if (skip_after(*this, depth - 1)) {
    throw Error("MLP configuration: skip_layer " + std::to_string(skip_layer) + " puts a skip after the last of " +
                std::to_string(depth) + " trunk layers; choose a depth that is not 1 more than a multiple of it");
  }
}

bool skip_after(const MlpConfig& config, size_t layer) {
  return config.skip_layer > 0 && layer > 0 && layer % config.skip_layer == 0;
}

size_t widest_hidden(const MlpConfig& c) {
  return c.view_dependence ? std::max({c.width, c.bottleneck_width, c.view_branch_width}) : c.width;
}

std::vector<const DenseLayer*> ParameterLayout::all() const {
  std::vector<const DenseLayer*> layers;
  for (const auto& layer : trunk) layers.push_back(&layer);
  layers.push_back(&density);
  if (view.out > 0) {
    layers.push_back(&bottleneck);
    layers.push_back(&view);
  }
  layers.push_back(&rgb);
  return layers;
}

ParameterLayout parameter_layout(const MlpConfig& config) {
  config.validate();
  ParameterLayout layout;
  size_t offset = 0;
  for (size_t i = 0; i < config.depth; ++i) {
    size_t in = config.width;
    if (i == 0) in = config.input_width;
    else if (skip_after(config, i - 1)) in = config.width + config.input_width;
    layout.trunk.push_back(make_layer("trunk " + std::to_string(i), in, config.width, offset));
  }
  layout.density = make_layer("density", config.width, config.density_outputs, offset);
  if (config.view_dependence) {
    layout.bottleneck = make_layer("bottleneck", config.width, config.bottleneck_width, offset);
    layout.view = make_layer("view", config.bottleneck_width + config.view_width, config.view_branch_width, offset);
    layout.rgb = make_layer("rgb", config.view_branch_width, config.rgb_outputs, offset);
  } else {
    layout.bottleneck.name = "bottleneck";
    layout.view.name = "view";
    layout.bottleneck.weight_offset = layout.bottleneck.bias_offset = offset;
    layout.view.weight_offset = layout.view.bias_offset = offset;
    layout.rgb = make_layer("rgb", config.width, config.rgb_outputs, offset);
  }
  layout.total = offset;
  return layout;
}

double init_limit(WeightInit init, size_t in, size_t out) {
  const double fan = init == WeightInit::he_uniform ? static_cast<double>(in) : static_cast<double>(in + out);
  return std::sqrt(6.0 / fan);
}

std::vector<float> initial_parameters(const MlpConfig& config) {
  const ParameterLayout layout = parameter_layout(config);
  std::vector<float> params(layout.total, 0.0f);  // biases stay zero
  const auto layers = layout.all();
  for (size_t l = 0; l < layers.size(); ++l) {
    const DenseLayer& layer = *layers[l];
    const double limit = init_limit(config.weight_init, layer.in, layer.out);
    const size_t count = layer.in * layer.out;
    for (size_t i = 0; i < count; i += 4) {
      const auto u = rng_uniform4(config.seed, static_cast<uint32_t>(i / 4), static_cast<uint32_t>(l), 0,
                                       kInitStream);
      for (size_t k = 0; k < 4 && i + k < count; ++k) {
        params[layer.weight_offset + i + k] = static_cast<float>((2.0 * u[k] - 1.0) * limit);
      }
    }
  }
  return params;
}

std::string describe(const MlpConfig& config) {
  const ParameterLayout layout = parameter_layout(config);
  std::ostringstream text;
  text << config.input_width << " → " << config.depth << "×" << config.width;
  if (config.skip_layer > 0 && config.depth > config.skip_layer + 1) text << " (skip after " << config.skip_layer << ")";
  text << " → density " << config.density_outputs << "; ";
  if (config.view_dependence) {
    text << "bottleneck " << config.bottleneck_width << " + view " << config.view_width << " → "
         << config.view_branch_width << " → ";
  }
  text << "rgb " << config.rgb_outputs << "; " << layout.total << " parameters";
  return text.str();
}

}  // namespace mipnerf::mlp
