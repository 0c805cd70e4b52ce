// Per-stage times from profiling events and host timers (see profiler.hpp).
#include "cl/profiler.hpp"

#include "cl/context.hpp"
#include "cl/error.hpp"
#include "core/error.hpp"

namespace mipnerf::ocl {
namespace {

const std::string kNoStage = "not in a stage";

cl_ulong event_time(const ::cl::Event& event, cl_profiling_info which, const std::string& stage) {
  cl_ulong ns = 0;
  check(event.getProfilingInfo(which, &ns),
        "clGetEventProfilingInfo (stage '" + stage + "'; was the queue made with profiling on?)");
  return ns;
}

}  // namespace

double StageProfile::stage_seconds() const {
  double sum = 0.0;
  for (const auto& s : stages) sum += s.seconds;
  return sum;
}

double StageProfile::seconds_with_prefix(const std::string& prefix) const {
  double sum = 0.0;
  for (const auto& s : stages) {
    if (s.stage.rfind(prefix, 0) == 0) sum += s.seconds;
  }
  return sum;
}

const StageTime* StageProfile::find(const std::string& stage) const {
  for (const auto& s : stages) {
    if (s.stage == stage) return &s;
  }
  return nullptr;
}

void StageProfiler::begin_step() {
  if (recording_) throw Error("stage profiler: begin_step twice without end_step");
  recording_ = true;
  pending_.clear();
  step_start_ = std::chrono::steady_clock::now();
}

void StageProfiler::end_step(Context& ctx) {
  if (!recording_) throw Error("stage profiler: end_step without begin_step");
  ctx.finish();
  profile_.wall_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - step_start_).count();
  ++profile_.steps;
  recording_ = false;
  for (const Pending& p : pending_) {
    if (p.event() == nullptr) continue;  // its enqueue failed (and threw)
    const cl_ulong end = event_time(p.event, CL_PROFILING_COMMAND_END, p.stage);
    const cl_ulong start = p.start_from() != nullptr ? event_time(p.start_from, CL_PROFILING_COMMAND_END, p.stage)
                                                     : event_time(p.event, CL_PROFILING_COMMAND_START, p.stage);
    StageTime& s = stage_named(p.stage);
    s.seconds += end > start ? static_cast<double>(end - start) * 1e-9 : 0.0;
    ++s.commands;
  }
  pending_.clear();
}

void StageProfiler::push_stage(const std::string& stage) { stack_.push_back(stage); }

void StageProfiler::pop_stage() {
  if (!stack_.empty()) stack_.pop_back();
}

const std::string& StageProfiler::current_stage() const { return stack_.empty() ? kNoStage : stack_.back(); }

::cl::Event* StageProfiler::next_event() {
  if (!recording_) return nullptr;
  stage_named(current_stage());  // listed in the order stages first ran, not the order their events are read
  pending_.push_back(Pending{current_stage(), ::cl::Event(), ::cl::Event()});
  return &pending_.back().event;
}

void StageProfiler::add_event_span(::cl::Event before, ::cl::Event after) {
  if (!recording_ || before() == nullptr || after() == nullptr) return;
  stage_named(current_stage());
  pending_.push_back(Pending{current_stage(), std::move(before), std::move(after)});
}

void StageProfiler::add_host_seconds(double seconds) {
  if (!recording_) return;
  StageTime& s = stage_named(current_stage());
  s.seconds += seconds;
  ++s.commands;
}

void StageProfiler::add_flops(double flops) {
  if (recording_) stage_named(current_stage()).flops += flops;
}

void StageProfiler::add_bytes(double bytes) {
  if (recording_) stage_named(current_stage()).bytes += bytes;
}

void add_stage_bytes(Context& ctx, double bytes) {
  if (StageProfiler* profiler = ctx.recording_profiler()) profiler->add_bytes(bytes);
}

StageTime& StageProfiler::stage_named(const std::string& stage) {
  const auto found = index_.find(stage);
  if (found != index_.end() && found->second < profile_.stages.size()) return profile_.stages[found->second];
  index_[stage] = profile_.stages.size();
  profile_.stages.push_back(StageTime{stage, 0.0, 0, 0.0, 0.0});
  return profile_.stages.back();
}

StageScope::StageScope(Context& ctx, const std::string& stage) : profiler_(ctx.profiler()) {
  if (profiler_) profiler_->push_stage(stage);
}

StageScope::~StageScope() {
  if (profiler_) profiler_->pop_stage();
}

HostTimer::HostTimer(Context& ctx)
    : profiler_(ctx.recording_profiler()),
      start_(std::chrono::steady_clock::now()) {}

HostTimer::~HostTimer() {
  if (profiler_) {
    profiler_->add_host_seconds(std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
  }
}

}  // namespace mipnerf::ocl
