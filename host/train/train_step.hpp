// One training step as a function (google/mipnerf's train_step): draw the batch, run this rank's chunks of it through
// the graph (coarse and fine, gradients accumulating), sum the gradients over ranks, check them, and apply Adam to
// every network, or skip the update when anything is not finite. The Trainer's loop only schedules around it.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "cl/context.hpp"
#include "data/device_dataset.hpp"
#include "graph/graph.hpp"
#include "mlp/adam.hpp"
#include "mlp/network.hpp"
#include "ops/batch.hpp"
#include "ops/loss.hpp"
#include "train/config.hpp"

namespace mipnerf::train {

// What a step works with; the Trainer owns every piece.
struct StepParts {
  ocl::Context& ctx;
  const TrainConfig& config;
  const graph::GraphSpec& spec;
  const data::DeviceDataset& data;
  ops::BatchArrays& batch;
  graph::Graph& graph;
  std::vector<std::unique_ptr<mlp::Network>>& networks;
  std::vector<std::unique_ptr<mlp::Adam>>& optimisers;
  std::vector<std::unique_ptr<mlp::GridTable>>& grids;  // Zip-NeRF's (empty for mip-NeRF)
  std::vector<std::unique_ptr<mlp::Adam>>& grid_optimisers;
  size_t chunk_rays;
};

// What a step did.
struct StepOutcome {
  std::vector<ops::LevelLoss> losses;  // per level, summed over the ranks
  double learning_rate = 0.0;          // eq. 24 at this step
  bool applied = false;                // false: a loss or gradient was not finite, and no update was applied
};

// Tests: called after the backward of the step, before the gradients are checked (e.g. to inject a NaN).
using AfterBackward = std::function<void(int64_t step, std::vector<std::unique_ptr<mlp::Network>>& networks)>;

// Step number `step` (1-based: the official learning rate and every random draw are keyed by it). Profiled under the
// stages "batch", the graph's, "allreduce …" and "adam" when the context has a profiler. `reduce_buffer` is reused.
StepOutcome train_step(StepParts& parts, int64_t step, const AfterBackward& after_backward,
                       std::vector<float>& reduce_buffer);

// The official learning-rate schedule of `config` (supplement eq. 24).
mlp::LrSchedule schedule_of(const TrainConfig& config);

}  // namespace mipnerf::train
