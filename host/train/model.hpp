// From a training configuration to the model it describes: the graph spec (levels, stages, options), the
// networks' configurations and the networks themselves, and how the configuration loads its data.
// Variants (mip-NeRF, NeRF, ablations) differ only in what make_graph_spec returns.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "cl/context.hpp"
#include "data/dataset.hpp"
#include "graph/graph_spec.hpp"
#include "mlp/grid_table.hpp"
#include "mlp/network.hpp"
#include "train/config.hpp"

namespace mipnerf::train {

// `multiscale_data`: the training split holds several scales (its pixels carry lossmult ≠ 1); the area
// loss is compiled in only then, and only when config.area_loss asks for it.
graph::GraphSpec make_graph_spec(const TrainConfig& config, bool multiscale_data);

// One network per entry of spec.mlps, freshly initialised (MlpConfig::seed), its products on `backend` (automatic:
// resolved for ctx's device by mlp::make_network).
std::vector<std::unique_ptr<mlp::Network>> make_networks(ocl::Context& ctx, const graph::GraphSpec& spec,
                                                        gemm::GemmBackend backend);

// One table per entry of spec.grids (Zip-NeRF; none for mip-NeRF), freshly initialised (GridConfig::seed).
std::vector<std::unique_ptr<mlp::GridTable>> make_grids(ocl::Context& ctx, const graph::GraphSpec& spec);

// An unbounded scene's sampling range when no near/far is given: from the camera out (camp_zipnerf 360.gin: near 0,
// far 1e6), not between a capture's depth bounds (the background lies beyond them).
inline constexpr double kUnboundedNear = 0.0;
inline constexpr double kUnboundedFar = 1e6;
// mip-NeRF 360's near (multinerf configs/360.gin: near 0.2): its reciprocal warp needs one > 0 (1/near).
inline constexpr double kContractedIpeNear = 0.2;

// How a run with `config` loads `data_path`: background, factor, near/far, and the multiscale pyramid
// (built on the fly when config.multiscale asks and the folder is not multiscale on disk). `scales` > 0
// forces that many scales.
data::LoadOptions load_options(const TrainConfig& config, const std::string& data_path, std::vector<std::string> splits,
                               int scales = 0);

}  // namespace mipnerf::train
