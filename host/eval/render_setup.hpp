// What rendering and evaluating a checkpoint share: the data it was trained on (and how to load it the same
// way), a chunk size that fits the device, where outputs go by default, and a record of the device.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "cl/device.hpp"
#include "data/dataset.hpp"
#include "io/json.hpp"
#include "train/checkpoint.hpp"

namespace mipnerf::eval {

// `requested` when given, else the data path the checkpoint records. Throws mipnerf::Error saying to pass
// --data when there is none, or when the recorded one no longer exists.
std::string resolve_data_path(const std::string& requested, const train::TrainedModel& model,
                              const std::string& checkpoint);

// Rays per render chunk: `requested` when > 0 (checked against the device's memory), else the largest power of
// two up to the model's render_chunk_rays that fits. Throws naming what to lower when nothing fits.
size_t render_chunk_rays(const train::TrainedModel& model, const ocl::DeviceInfo& device, size_t requested);
// The same for the networks of `spec`, up to `configured_chunk` (render_chunk_rays).
size_t render_chunk_rays(const graph::GraphSpec& spec, size_t configured_chunk, const ocl::DeviceInfo& device,
                         size_t requested);

// The run folder a checkpoint belongs to: RUN for RUN/checkpoints/ckpt_N.mnck, else the file's folder (relative
// paths stay relative; "." for a file in the working folder).
std::string run_folder_of(const std::string& checkpoint);

// name, platform, vendor, type, driver version, OpenCL C version, compute units, global memory.
io::Json device_record(const ocl::DeviceInfo& device);

// Parameters of all networks of the model.
size_t parameter_count(const train::TrainedModel& model);

}  // namespace mipnerf::eval
