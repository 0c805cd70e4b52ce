// The MLP's configuration (paper defaults), its flat parameter layout, and its uniform initialisation (Glorot's, the
// paper's; He's, multinerf's and camp_zipnerf's).
//
// Architecture (mip-NeRF supplement §5; google/mipnerf internal/models.py MLP):
//   features [rows][input_width] → `depth` dense layers of `width` with ReLU; the features are concatenated
//   again to the activation of every trunk layer i with i % skip_layer == 0 and i > 0 (0-based, as the
//   official code: with depth 8 and skip_layer 4, after layer index 4) → density head (density_outputs, no
//   activation). With view dependence: bottleneck dense layer (bottleneck_width, no activation) of the trunk
//   output, concatenated with the per-ray view encoding (view_width) → one dense layer of view_branch_width
//   with ReLU → rgb head (rgb_outputs). Without view dependence the rgb head reads the trunk output and the
//   bottleneck and view layers do not exist.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/enum_names.hpp"

namespace mipnerf::mlp {

// How the weights are drawn (biases start at zero either way): both uniform on (−a, a), a from the layer's widths.
enum class WeightInit {
  glorot_uniform,  // a = √(6 / (in + out)): flax's Dense default, google/mipnerf's (the paper's)
  he_uniform,      // a = √(6 / in): multinerf's and camp_zipnerf's MLP weight_init 'he_uniform' (√2 × wider when in = out)
};
constexpr std::array<EnumName<WeightInit>, 2> enum_names(WeightInit) {
  return {{{WeightInit::glorot_uniform, "glorot_uniform"}, {WeightInit::he_uniform, "he_uniform"}}};
}

struct MlpConfig {
  size_t input_width = 96;         // per-sample features: IPE 2·3·L = 96 for L = 16; NeRF's PE with identity: 63
  size_t depth = 8;                // dense ReLU layers of the trunk
  size_t width = 256;              // units per trunk layer (W)
  size_t skip_layer = 4;           // features re-concatenated after trunk layer i when i % skip_layer == 0, i > 0; 0: never
  bool view_dependence = true;     // colour conditioned on the view direction; false leaves the view branch out
  size_t view_width = 27;          // per-ray view-direction encoding: identity + degrees 0..3 sin/cos = 27
  size_t view_branch_width = 128;  // units of the view branch's one ReLU layer
  size_t bottleneck_width = 256;   // units of the bottleneck layer (no activation) feeding the view branch
  size_t density_outputs = 1;      // raw density channels
  size_t rgb_outputs = 3;          // raw colour channels
  uint64_t seed = 0;               // seed of the initial weights (biases start at zero)
  WeightInit weight_init = WeightInit::glorot_uniform;

  // Throws mipnerf::Error naming the field when a width is zero or the last trunk layer would be a skip
  // point (its concatenation would feed the heads, which this implementation does not support).
  void validate() const;
};

// One dense layer inside the flat parameter buffer: weights [in][out] row-major at weight_offset, then
// biases [out] at bias_offset. A layer whose input is a concatenation [a | b] stores a's rows first.
struct DenseLayer {
  std::string name;  // "trunk 0" … "trunk 7", "density", "bottleneck", "view", "rgb"
  size_t in = 0;     // input width (sum of the concatenated parts)
  size_t out = 0;    // output width
  size_t weight_offset = 0;
  size_t bias_offset = 0;
  size_t parameter_count() const { return in * out + out; }
};

// Every layer's place in the flat buffer, in this order: trunk 0 … depth−1, density, then bottleneck and
// view (only with view dependence), then rgb.
struct ParameterLayout {
  std::vector<DenseLayer> trunk;
  DenseLayer density;
  DenseLayer bottleneck;  // out == 0 without view dependence
  DenseLayer view;        // out == 0 without view dependence
  DenseLayer rgb;
  size_t total = 0;       // floats in the flat parameter (and gradient) buffer

  std::vector<const DenseLayer*> all() const;  // the layers that exist, in buffer order
};

// True when the features are concatenated to the activation of trunk layer `layer` (official rule).
bool skip_after(const MlpConfig& config, size_t layer);

// The widest hidden layer: the trunk, or with view dependence the bottleneck or view branch when wider (the columns
// a buffer that holds any hidden activation needs).
size_t widest_hidden(const MlpConfig& config);

ParameterLayout parameter_layout(const MlpConfig& config);

// The initial parameters: weights U(−a, a) with a = init_limit(config.weight_init, in, out), in = the layer's full
// (concatenated) input width, and zero biases, as the official codes' flax Dense layers. A pure function of
// config.seed and weight_init (Philox4x32-10 on the host, so every platform draws the same numbers).
std::vector<float> initial_parameters(const MlpConfig& config);
double init_limit(WeightInit init, size_t in, size_t out);

// One line, e.g. "96 → 8×256 (skip after 4) → density 1; bottleneck 256 + view 27 → 128 → rgb 3; 612740 params".
std::string describe(const MlpConfig& config);

}  // namespace mipnerf::mlp
