// From a training configuration to the model it describes: the graph spec (levels, stages, options) and
// the networks' configurations. Variants (mip-NeRF, NeRF, ablations) differ only in what this returns.
#pragma once

#include "graph/graph_spec.hpp"
#include "train/config.hpp"

namespace mipnerf::train {

// `multiscale_data`: the training split holds several scales (its pixels carry lossmult ≠ 1); the area
// loss is compiled in only then, and only when config.area_loss asks for it.
graph::GraphSpec make_graph_spec(const TrainConfig& config, bool multiscale_data);

}  // namespace mipnerf::train
