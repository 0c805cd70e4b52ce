// A step's time by stage, as a table: what `mipnerf-cl bench` puts beside each preset's timing and what
// `mipnerf-cl train --profile` prints and writes (profile.md). Figures are per profiled step.
//
// The GEMM-bound limit is the rate the step would reach if everything but the MLP's products took no time:
// batch rays / (seconds of the "gemm …" stages per step). The step's rate as a fraction of it (= GEMM seconds /
// step seconds) says how much is left to gain outside the products; the products' GFLOP/s say how close they run
// to the BLAS itself.
#pragma once

#include "io/json.hpp"

#include <cstddef>
#include <string>

#include <nlohmann/json.hpp>

#include "cl/profiler.hpp"

namespace mipnerf::bench {

struct GemmLimit {
  double step_seconds = 0.0;          // wall seconds per profiled step
  double gemm_seconds = 0.0;          // seconds of the "gemm …" stages per step
  double gemm_gflops = 0.0;           // their FLOPs / their seconds, 1e9/s
  double rays_per_second = 0.0;       // batch / step_seconds
  double limit_rays_per_second = 0.0; // batch / gemm_seconds
  double fraction() const { return step_seconds > 0 ? gemm_seconds / step_seconds : 0.0; }
};

GemmLimit gemm_limit(const ocl::StageProfile& profile, size_t rays_per_step);

// Stages by share of the step (largest first), then "not in a stage", then the GEMM-bound line.
// With `machine` (probe_machine()), the products' rate is also given as a fraction of the machine's FMA peak and of
// its large-sgemm rate.
// `unit` names what one profiled "step" is: "step" for training, "image" for a render.
std::string stage_profile_markdown(const ocl::StageProfile& profile, size_t rays_per_step,
                                   const io::Json& machine = io::Json::object(), const std::string& unit = "step");

nlohmann::ordered_json stage_profile_json(const ocl::StageProfile& profile, size_t rays_per_step);

}  // namespace mipnerf::bench
