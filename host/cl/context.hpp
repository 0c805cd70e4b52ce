// One long-lived OpenCL context, in-order queue and program cache for a run, on the chosen device.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "cl/device.hpp"
#include "cl/device_quirks.hpp"
#include "core/log.hpp"
#include "cl/opencl.hpp"
#include "cl/profiler.hpp"
#include "cl/program.hpp"

namespace mipnerf::ocl {

struct ContextOptions {
  std::string device_selector;  // --device: index or name substring; empty = first GPU, else first CPU
  bool profiling = false;       // enable event profiling on the queue (benchmarks)
};

class Context {
 public:
  explicit Context(const DeviceInfo& device, bool profiling = false);
  static std::unique_ptr<Context> create(const ContextOptions& options);

  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  const DeviceInfo& device_info() const { return device_; }
  const DeviceTraits& traits() const { return traits_; }
  ::cl::Context& context() { return context_; }
  ::cl::CommandQueue& queue() { return queue_; }
  cl_command_queue raw_queue() { return queue_(); }
  cl_device_id raw_device() const { return device_.device(); }

  // The program made of embedded kernels/<files> built with `options` (plus the device's base options).
  Program& program(const std::vector<std::string>& files, const BuildOptions& options = {});
  // Same, from given sources (tests, tools).
  Program& program_from_sources(const std::vector<SourceFile>& files, const BuildOptions& options = {});
  const ProgramCache& program_cache() const { return programs_; }
  // Adds options to those every program of this context is built with from now on (the device's base options; the
  // program cache keys on them, so nothing built before is reused with them). mipnerf-selftest's --inject-define.
  void add_base_options(const BuildOptions& options) { traits_.base_options.merge(options); }

  void finish();  // clFinish, checked

  // The stage profiler recording this context's commands, or nullptr (the default). Not owned; see profiler.hpp.
  StageProfiler* profiler() const { return profiler_; }
  // The profiler while it records a step (between begin_step and end_step), else nullptr: what code that adds to a
  // profile asks for.
  StageProfiler* recording_profiler() const { return profiler_ && profiler_->recording() ? profiler_ : nullptr; }
  void set_profiler(StageProfiler* profiler);  // needs a queue made with profiling on
  bool profiling_queue() const { return profiling_queue_; }

  void set_log(LogFn log) {
    log_ = log;
    programs_.set_log(std::move(log));
  }
  void log(LogLevel level, const std::string& message) const {
    if (log_) log_(level, message);
  }

 private:
  DeviceInfo device_;
  DeviceTraits traits_;
  ::cl::Context context_;
  ::cl::CommandQueue queue_;
  ProgramCache programs_;
  LogFn log_;
  bool profiling_queue_ = false;
  StageProfiler* profiler_ = nullptr;
};

}  // namespace mipnerf::ocl
