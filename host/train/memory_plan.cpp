// Chunk sizes from the device's memory.
#include "train/memory_plan.hpp"

#include <algorithm>
#include <cstdio>

#include "core/error.hpp"
#include "data/device_dataset.hpp"
#include "graph/graph.hpp"
#include "mlp/adam.hpp"
#include "mlp/network.hpp"
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

FixedBytes training_fixed_bytes(const data::Split& train_split, const graph::GraphSpec& spec, size_t batch_rays) {
  // Summed from the owners rather than copied here: an earlier hand-written sum counted 32 floats per camera where
  // the device stride is camera_layout::stride = 24, and left out the pixel offsets and Adam's reduction partials.
  FixedBytes fixed;
  fixed.data = data::DeviceDataset::bytes_for(train_split);
  fixed.batch = ops::BatchArrays::bytes_for(batch_rays);
  fixed.largest_buffer = std::max(data::DeviceDataset::largest_buffer_for(train_split), fixed.batch);
  for (const auto& network : spec.mlps) {
    const size_t parameters = mlp::parameter_layout(network).total;
    fixed.networks += mlp::Network::bytes_for(network) + mlp::Adam::bytes_for(parameters);
    fixed.largest_buffer = std::max(fixed.largest_buffer, parameters * sizeof(float));
  }
  return fixed;
}

FixedBytes rendering_fixed_bytes(const graph::GraphSpec& spec) {
  FixedBytes fixed;
  for (const auto& network : spec.mlps) {
    fixed.networks += mlp::Network::bytes_for(network);
    fixed.largest_buffer = std::max(fixed.largest_buffer, mlp::parameter_layout(network).total * sizeof(float));
  }
  return fixed;
}

size_t largest_graph_buffer(const graph::GraphSpec& spec, size_t chunk_rays) {
  size_t widest = static_cast<size_t>(std::max(spec.position_encoding.ipe_width(), spec.position_encoding.pe_width()));
  for (const auto& m : spec.mlps) widest = std::max({widest, m.width, m.input_width + m.width, m.bottleneck_width});
  return chunk_rays * spec.max_intervals() * widest * sizeof(float);
}

namespace {

// Why the fixed part does not fit, naming its largest owner's setting.
[[noreturn]] void fixed_does_not_fit(const FixedBytes& fixed, const std::string& need, const std::string& device_text) {
  std::string advice;
  if (fixed.data >= fixed.batch && fixed.data >= fixed.networks) {
    advice = "the training images take " + mib(fixed.data) +
             ": train at a lower resolution (factor = 2, 4, ...) or on fewer images";
  } else if (fixed.batch >= fixed.networks) {
    advice = "the batch arrays take " + mib(fixed.batch) + ": lower batch_size";
  } else {
    advice = "the networks and their optimiser state take " + mib(fixed.networks) + ": lower mlp_width";
  }
  throw Error("the data, batch and networks alone need " + need + " on " + device_text + "); " + advice +
              " (on PoCL, POCL_MEMORY_LIMIT=<GiB> sets how much memory the device offers)");
}

}  // namespace

MemoryPlan plan_memory(const graph::GraphSpec& spec, const ocl::DeviceInfo& device, size_t batch_rays,
                       const FixedBytes& fixed, size_t requested_chunk, bool training) {
  const graph::GraphMode mode = training ? graph::GraphMode::training : graph::GraphMode::inference;
  const size_t fixed_total = fixed.total();
  MemoryPlan plan;
  plan.fixed_bytes = fixed_total;
  plan.budget_bytes = static_cast<size_t>(kMemoryBudgetFraction * static_cast<double>(device.global_mem_bytes));
  auto graph_bytes = [&](size_t chunk) { return graph::Graph::bytes_for(spec, mode, chunk, training ? batch_rays : 0); };
  auto fits = [&](size_t chunk) {
    return fixed_total + graph_bytes(chunk) <= plan.budget_bytes &&
           largest_graph_buffer(spec, chunk) <= device.max_alloc_bytes;
  };
  auto fill = [&](size_t chunk) {
    plan.chunk_rays = chunk;
    plan.graph_bytes = graph_bytes(chunk);
    plan.largest_buffer = std::max(largest_graph_buffer(spec, chunk), fixed.largest_buffer);
    return plan;
  };
  const std::string device_text = "'" + device.name + "' (" + mib(device.global_mem_bytes) + " global, " +
                                  mib(device.max_alloc_bytes) + " per allocation";
  if (fixed_total > plan.budget_bytes) {
    fixed_does_not_fit(fixed, mib(fixed_total) + ", more than the " + mib(plan.budget_bytes) + " budget", device_text);
  }
  if (fixed.largest_buffer > device.max_alloc_bytes) {
    fixed_does_not_fit(fixed, "a single buffer of " + mib(fixed.largest_buffer), device_text);
  }
  const std::string chunk_setting = training ? "chunk_rays" : "--chunk (render_chunk_rays)";
  if (requested_chunk > 0) {
    if (!fits(requested_chunk)) {
      throw Error(chunk_setting + " = " + std::to_string(requested_chunk) + " needs " +
                  mib(fixed_total + graph_bytes(requested_chunk)) + " on " + device_text + "): lower " + chunk_setting +
                  (training ? ", or set it to 0 to choose automatically" : ""));
    }
    return fill(requested_chunk);
  }
  size_t chunk = 1;
  while (chunk * 2 <= std::max<size_t>(batch_rays, 1) && fits(chunk * 2)) chunk *= 2;
  if (!fits(chunk)) {
    throw Error("even one ray per chunk needs more memory than " + device_text + ") allows: lower " +
                (training ? "batch_size, " : "") + "num_samples, mlp_width or pos_max_deg");
  }
  // Not a power of two, but all of the batch fits: one chunk.
  if (training && batch_rays > chunk && fits(batch_rays)) chunk = batch_rays;
  return fill(chunk);
}

}  // namespace mipnerf::train
