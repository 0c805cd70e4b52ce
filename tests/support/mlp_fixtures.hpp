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

// FLOPs of the colour head's forward products over `rows` samples of `rays` rays, counted from the architecture
// (mlp.hpp): with view dependence the bottleneck, the view layer (its view-encoding part once per ray) and the rgb
// layer; without, the rgb layer on the trunk's output. What a density-only forward leaves out.
inline double colour_head_flops(const mlp::MlpConfig& c, double rows, double rays) {
  if (!c.view_dependence) return 2.0 * rows * c.width * c.rgb_outputs;
  return 2.0 * (rows * (c.width * c.bottleneck_width + c.bottleneck_width * c.view_branch_width +
                        c.view_branch_width * c.rgb_outputs) +
                rays * c.view_width * c.view_branch_width);
}

}  // namespace mipnerf::test
