// One long-lived OpenCL context, queue and program cache for a run.
#include "cl/context.hpp"

#include "cl/error.hpp"
#include "core/error.hpp"

namespace mipnerf::ocl {
namespace {

::cl::Context make_context(const DeviceInfo& device) {
  cl_int status = CL_SUCCESS;
  ::cl::Context context(device.device, nullptr, nullptr, nullptr, &status);
  check(status, "clCreateContext(" + device.name + ")");
  return context;
}

::cl::CommandQueue make_queue(const ::cl::Context& context, const DeviceInfo& device, bool profiling) {
  cl_int status = CL_SUCCESS;
  ::cl::CommandQueue queue(context, device.device, profiling ? CL_QUEUE_PROFILING_ENABLE : 0, &status);
  check(status, "clCreateCommandQueue(" + device.name + ")");
  return queue;
}

}  // namespace

Context::Context(const DeviceInfo& device, bool profiling)
    : device_(device),
      traits_(traits_for(device)),
      context_(make_context(device)),
      queue_(make_queue(context_, device, profiling)),
      programs_(context_, device.device, device.name),
      profiling_queue_(profiling) {}

std::unique_ptr<Context> Context::create(const ContextOptions& options) {
  const auto devices = list_devices();
  return std::make_unique<Context>(choose_device(devices, options.device_selector), options.profiling);
}

Program& Context::program(const std::vector<std::string>& files, const BuildOptions& options) {
  return program_from_sources(embedded_sources(files), options);
}

Program& Context::program_from_sources(const std::vector<SourceFile>& files, const BuildOptions& options) {
  BuildOptions all = traits_.base_options;
  all.merge(options);
  return programs_.get(files, all);
}

void Context::set_profiler(StageProfiler* profiler) {
  if (profiler != nullptr && !profiling_queue_) {
    throw Error("stage profiler on " + device_.name +
                ": the context's queue was made without profiling; open it with ContextOptions::profiling");
  }
  profiler_ = profiler;
}

void Context::finish() { check(queue_.finish(), "clFinish"); }

}  // namespace mipnerf::ocl
