// How many rays a chunk can hold on a device: the memory a configuration needs, estimated before anything
// is allocated, against the device's global memory and its single-allocation limit.
#pragma once

#include <cstddef>
#include <string>

#include "cl/device.hpp"
#include "data/dataset.hpp"
#include "graph/graph_spec.hpp"

namespace mipnerf::train {

// What a run keeps on the device whatever the chunk size, by owner, so that a plan that does not fit can name the
// setting to lower.
struct FixedBytes {
  size_t data = 0;            // the training split (data::DeviceDataset): lower `factor`, or use fewer images
  size_t batch = 0;           // the batch arrays (ops::BatchArrays): lower `batch_size`
  size_t networks = 0;        // parameters, gradients, optimiser state (mlp::Network, mlp::Adam): lower `mlp_width`
  size_t largest_buffer = 0;  // the biggest single one of them (the split's pixels, usually)
  size_t total() const { return data + batch + networks; }
};

struct MemoryPlan {
  size_t chunk_rays = 0;        // rays per chunk
  size_t graph_bytes = 0;       // the graph's buffers and MLP workspaces at that chunk size
  size_t fixed_bytes = 0;       // dataset, networks, optimiser state, batch arrays
  size_t largest_buffer = 0;    // the biggest single allocation (must fit CL_DEVICE_MAX_MEM_ALLOC_SIZE)
  size_t budget_bytes = 0;      // what the plan allows itself of the device's global memory
  size_t total() const { return graph_bytes + fixed_bytes; }
  std::string describe() const;  // "chunk 1024 rays, 812 MiB (graph 700 + fixed 112) of 3.0 GiB budget"
};

// Fraction of the device's global memory a run may plan for (the rest: driver, CLBlast temporaries).
constexpr double kMemoryBudgetFraction = 0.75;

// The largest chunk (a power of two, at most batch_rays) that fits, or `requested_chunk` when > 0 (checked).
// Called before anything of the run is allocated on the device. Throws mipnerf::Error saying which setting to
// lower when nothing fits: `training` names the training settings (chunk_rays, batch_size), else the render's
// (--chunk, render_chunk_rays).
MemoryPlan plan_memory(const graph::GraphSpec& spec, const ocl::DeviceInfo& device, size_t batch_rays,
                       const FixedBytes& fixed, size_t requested_chunk, bool training);

// What a training run keeps on the device whatever the chunk size, from each owner's bytes_for: the training
// split (data::DeviceDataset), every network's parameters and gradients (mlp::Network), their optimisers (mlp::Adam)
// and the batch arrays (ops::BatchArrays). The `fixed` of a training plan.
FixedBytes training_fixed_bytes(const data::Split& train_split, const graph::GraphSpec& spec, size_t batch_rays);
// What rendering keeps: the networks (mlp::Network::bytes_for).
FixedBytes rendering_fixed_bytes(const graph::GraphSpec& spec);

// The largest single buffer the graph allocates for a chunk of `chunk_rays` (features or an MLP layer).
size_t largest_graph_buffer(const graph::GraphSpec& spec, size_t chunk_rays);

}  // namespace mipnerf::train
