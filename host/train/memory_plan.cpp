// Chunk sizes from the device's memory.
#include "train/memory_plan.hpp"

#include <algorithm>
#include <cstdio>

#include "core/error.hpp"
#include "data/device_dataset.hpp"
#include "graph/graph.hpp"
#include "mlp/adam.hpp"
#include "mlp/mlp.hpp"
#include "ops/batch.hpp"

namespace mipnerf::train {
namespace {

std::string mib(size_t bytes) { return std::to_string((bytes + (1u << 20) - 1) >> 20) + " MiB"; }

}  // namespace

std::string MemoryPlan::describe() const {
  char text[200];
  std::snprintf(text, sizeof(text), "chunk %zu rays: %s planned (graph %s + data, networks and optimiser %s) of a %s budget",
                chunk_rays, mib(total()).c_str(), mib(graph_bytes).c_str(), mib(fixed_bytes).c_str(),
                mib(budget_bytes).c_str());
  return text;
}

size_t training_fixed_bytes(const data::Split& train_split, const graph::GraphSpec& spec, size_t batch_rays) {
  // Summed from the owners rather than copied here: an earlier hand-written sum counted 32 floats per camera where
  // the device stride is camera_layout::stride = 24, and left out the pixel offsets and Adam's reduction partials.
  size_t bytes = data::DeviceDataset::bytes_for(train_split) + ops::BatchArrays::bytes_for(batch_rays);
  for (const auto& network : spec.mlps) {
    bytes += mlp::Mlp::bytes_for(network) + mlp::Adam::bytes_for(mlp::parameter_layout(network).total);
  }
  return bytes;
}

size_t largest_graph_buffer(const graph::GraphSpec& spec, size_t chunk_rays) {
  size_t widest = static_cast<size_t>(std::max(spec.position_encoding.ipe_width(), spec.position_encoding.pe_width()));
  for (const auto& m : spec.mlps) widest = std::max({widest, m.width, m.input_width + m.width, m.bottleneck_width});
  return chunk_rays * spec.max_intervals() * widest * sizeof(float);
}

MemoryPlan plan_memory(const graph::GraphSpec& spec, const ocl::DeviceInfo& device, size_t batch_rays,
                       size_t fixed_bytes, size_t requested_chunk, bool training) {
  const graph::GraphMode mode = training ? graph::GraphMode::training : graph::GraphMode::inference;
  MemoryPlan plan;
  plan.fixed_bytes = fixed_bytes;
  plan.budget_bytes = static_cast<size_t>(kMemoryBudgetFraction * static_cast<double>(device.global_mem_bytes));
  auto fits = [&](size_t chunk) {
    return fixed_bytes + graph::Graph::bytes_for(spec, mode, chunk, training ? batch_rays : 0) <= plan.budget_bytes &&
           largest_graph_buffer(spec, chunk) <= device.max_alloc_bytes;
  };
  auto fill = [&](size_t chunk) {
    plan.chunk_rays = chunk;
    plan.graph_bytes = graph::Graph::bytes_for(spec, mode, chunk, training ? batch_rays : 0);
    plan.largest_buffer = largest_graph_buffer(spec, chunk);
    return plan;
  };
  const std::string device_text = "'" + device.name + "' (" + mib(device.global_mem_bytes) + " global, " +
                                  mib(device.max_alloc_bytes) + " per allocation";
  if (fixed_bytes > plan.budget_bytes) {
    throw Error("the dataset and networks alone need " + mib(fixed_bytes) + ", more than the " + mib(plan.budget_bytes) +
                " budget on " + device_text + "): use fewer or smaller images (or set POCL_MEMORY_LIMIT on PoCL)");
  }
  if (requested_chunk > 0) {
    if (!fits(requested_chunk)) {
      throw Error("chunk_rays = " + std::to_string(requested_chunk) + " needs " +
                  mib(fixed_bytes + graph::Graph::bytes_for(spec, mode, requested_chunk, batch_rays)) + " on " +
                  device_text + "): lower chunk_rays, or set it to 0 to choose automatically");
    }
    return fill(requested_chunk);
  }
  size_t chunk = 1;
  while (chunk * 2 <= std::max<size_t>(batch_rays, 1) && fits(chunk * 2)) chunk *= 2;
  if (!fits(chunk)) {
    throw Error("even one ray per chunk needs more memory than " + device_text +
                ") allows: lower num_samples, mlp_width or pos_max_deg");
  }
  // Not a power of two, but all of the batch fits: one chunk.
  if (training && batch_rays > chunk && fits(batch_rays)) chunk = batch_rays;
  return fill(chunk);
}

}  // namespace mipnerf::train
