// A small MLP configuration shared by the tests that need a real network but not the paper's size: every part of
// the network is present (skip, bottleneck, view branch) at widths that run in milliseconds.
#pragma once

#include "mlp/mlp_config.hpp"

namespace mipnerf::test {

// 6 features → 4 × 16 (skip after layer index 2) → density; bottleneck 10 + view 5 → 12 → rgb.
inline mlp::MlpConfig small_mlp_config(bool view_dependence = true) {
  mlp::MlpConfig c;
  c.input_width = 6;
  c.depth = 4;
  c.width = 16;
  c.skip_layer = 2;
  c.view_dependence = view_dependence;
  c.view_width = 5;
  c.view_branch_width = 12;
  c.bottleneck_width = 10;
  c.density_outputs = 1;
  c.rgb_outputs = 3;
  c.seed = 3;
  return c;
}

}  // namespace mipnerf::test
