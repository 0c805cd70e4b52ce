// Data, chunk size, output folder and device record for render and eval.
#include "eval/render_setup.hpp"

#include <filesystem>

#include "core/error.hpp"
#include "train/memory_plan.hpp"

namespace mipnerf::eval {
namespace fs = std::filesystem;

std::string resolve_data_path(const std::string& requested, const train::TrainedModel& model,
                              const std::string& checkpoint) {
  if (!requested.empty()) return requested;
  if (model.data_path.empty()) {
    throw Error(checkpoint + " does not record the data it was trained on: pass --data DIR");
  }
  std::error_code ec;
  if (!fs::exists(model.data_path, ec)) {
    throw Error(checkpoint + " was trained on " + model.data_path + ", which no longer exists: pass --data DIR");
  }
  return model.data_path;
}

size_t render_chunk_rays(const train::TrainedModel& model, const ocl::DeviceInfo& device, size_t requested) {
  return render_chunk_rays(model.spec, static_cast<size_t>(model.config.render_chunk_rays), device, requested);
}

size_t render_chunk_rays(const graph::GraphSpec& spec, size_t configured_chunk, const ocl::DeviceInfo& device,
                         size_t requested) {
  const size_t upper = requested > 0 ? requested : configured_chunk;
  return train::plan_memory(spec, device, upper, train::rendering_fixed_bytes(spec), requested, false).chunk_rays;
}

std::string run_folder_of(const std::string& checkpoint) {
  const fs::path folder = fs::path(checkpoint).lexically_normal().parent_path();
  const fs::path run = folder.filename() == "checkpoints" ? folder.parent_path() : folder;
  return run.empty() ? std::string(".") : run.string();
}

io::Json device_record(const ocl::DeviceInfo& device) {
  return {{"name", device.name},
          {"platform", device.platform_name},
          {"vendor", device.vendor},
          {"type", device.type_name()},
          {"driver_version", device.driver_version},
          {"opencl_c_version", device.opencl_c_version},
          {"compute_units", device.compute_units},
          {"global_memory_bytes", device.global_mem_bytes}};
}

size_t parameter_count(const train::TrainedModel& model) {
  size_t n = 0;
  for (const auto& network : model.networks) n += network->parameter_count();
  return n;
}

}  // namespace mipnerf::eval
