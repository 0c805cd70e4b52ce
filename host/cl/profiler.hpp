// Where a step's time goes: per-stage device time from OpenCL profiling events, host time from host timers.
//
// A StageProfiler attached to a Context (Context::set_profiler; the queue must have been made with profiling on)
// records every command enqueued through the project's launch and buffer helpers under the innermost open
// StageScope's name. Work done on the host (the host BLAS backend's products) is added with add_host_seconds. The
// caller brackets what it measures with begin_step / end_step; end_step waits for the queue, reads the events'
// start and end times and adds them to the stages. Unattached (the default), a StageScope costs one pointer test.
//
// Device and host times of different stages never overlap on an in-order queue whose host work runs only while the
// queue is drained (the host GEMM maps its buffers blocking), so the stages' times add up to at most the step's
// wall time; what is left is launch overhead and host time between commands ("not in a stage" in the report).
#pragma once

#include <chrono>
#include <deque>
#include <map>
#include <string>
#include <vector>

#include "cl/opencl.hpp"

namespace mipnerf::ocl {

class Context;

// One stage's totals over the profiled steps.
struct StageTime {
  std::string stage;
  double seconds = 0.0;  // device time of its commands (events) plus host time added to it
  size_t commands = 0;   // commands (kernels, copies, fills, products) it ran
  double flops = 0.0;    // floating-point operations it declared (GEMMs), 0 otherwise
  double bytes = 0.0;    // memory traffic it declared: the least its commands move (each input read once, each output
                         // written once; graph/stage_traffic.hpp), 0 where none was declared
};

// Totals of the profiled steps, stages in the order they first ran.
struct StageProfile {
  size_t steps = 0;
  double wall_seconds = 0.0;  // host wall time from begin_step to the end of end_step's wait, summed
  std::vector<StageTime> stages;

  double stage_seconds() const;                  // Σ stages
  double seconds_with_prefix(const std::string& prefix) const;  // Σ stages whose name starts with prefix
  const StageTime* find(const std::string& stage) const;
};

class StageProfiler {
 public:
  StageProfiler() = default;
  StageProfiler(const StageProfiler&) = delete;
  StageProfiler& operator=(const StageProfiler&) = delete;

  // Recording happens only between begin_step and end_step; commands outside are not recorded.
  void begin_step();
  void end_step(Context& ctx);  // clFinish, then the events' times
  bool recording() const { return recording_; }

  void push_stage(const std::string& stage);
  void pop_stage();
  const std::string& current_stage() const;

  // An event for the next command of the current stage, or nullptr when not recording.
  ::cl::Event* next_event();
  // A command measured by two events (e.g. a library routine that enqueues several kernels: a marker before it and
  // its last kernel's event): its time is from the first's end to the second's end.
  void add_event_span(::cl::Event before, ::cl::Event after);
  void add_host_seconds(double seconds);  // to the current stage, one command
  void add_flops(double flops);           // to the current stage
  void add_bytes(double bytes);           // to the current stage

  const StageProfile& profile() const { return profile_; }
  void reset() {
    profile_ = StageProfile{};
    index_.clear();
  }

 private:
  StageTime& stage_named(const std::string& stage);

  struct Pending {
    std::string stage;
    ::cl::Event start_from;  // null: the event's own start
    ::cl::Event event;
  };
  bool recording_ = false;
  std::chrono::steady_clock::time_point step_start_;
  std::vector<std::string> stack_;
  std::deque<Pending> pending_;  // a deque: next_event's pointer stays valid while more are added
  std::map<std::string, size_t> index_;
  StageProfile profile_;
};

// Names the stage of the commands enqueued on ctx while it lives (no-op when ctx has no profiler).
class StageScope {
 public:
  StageScope(Context& ctx, const std::string& stage);
  ~StageScope();
  StageScope(const StageScope&) = delete;
  StageScope& operator=(const StageScope&) = delete;

 private:
  StageProfiler* profiler_;
};

// Declares the least memory traffic of the current stage's commands (no-op when not recording).
void add_stage_bytes(Context& ctx, double bytes);

// Host work of the current stage timed while it lives (no-op when not recording).
class HostTimer {
 public:
  explicit HostTimer(Context& ctx);
  ~HostTimer();
  HostTimer(const HostTimer&) = delete;
  HostTimer& operator=(const HostTimer&) = delete;

 private:
  StageProfiler* profiler_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace mipnerf::ocl
