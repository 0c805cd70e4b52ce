// `train --minutes N`: the step count a wall-clock budget buys, measured by a short timed warm-up before step 1 and
// then recorded in the run (config.json's "time_budget", OUT/time_budget.json, every checkpoint's config), so a
// resume or a reproduction trains exactly that many steps instead of measuring again.
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

namespace mipnerf::train {

// The warm-up's rule: the first step is cold (first-touch allocations, lazily built programs, caches) and is timed
// apart; then warm steps are timed until there are at least kMinWarmSteps of them and they took at least
// warmup_target_seconds(budget), or kMaxWarmSteps were taken. The warm-up's steps are thrown away afterwards (the
// networks and Adam are put back to their initial state), but its time is spent from the budget.
inline constexpr int64_t kMinWarmSteps = 3;
inline constexpr int64_t kMaxWarmSteps = 50;
// Seconds of warm steps to time for a budget: 2 % of it, at most 10 s (a longer sample only delays step 1).
double warmup_target_seconds(double budget_seconds);
// Whether the warm-up has timed enough warm steps (the rule above).
bool warmup_done(int64_t warm_steps, double warm_seconds, double budget_seconds);

// What a warm-up measured and the step count it chose.
struct StepBudget {
  double budget_seconds = 0.0;     // the wall-clock budget (train --minutes × 60)
  double cold_step_seconds = 0.0;  // the first step, not counted in seconds_per_step
  int64_t warm_steps = 0;          // timed steps after the cold one
  double warm_seconds = 0.0;       // their wall time
  double seconds_per_step = 0.0;   // warm_seconds / warm_steps
  int64_t steps = 0;               // the run's step count (its learning-rate schedule spans them)

  // The whole warm-up, spent from the budget: the cold step and the warm ones.
  double warmup_seconds() const { return cold_step_seconds + warm_seconds; }
  // One line for logs and config.json: the budget, what was measured, the steps chosen.
  std::string describe() const;
  nlohmann::ordered_json to_json() const;
};

// floor((budget − warm-up) / s_per_step): the steps that fit in what the warm-up left of the budget. Throws
// mipnerf::Error when not one step fits (a budget shorter than the warm-up), saying the smallest budget that would.
int64_t steps_for_budget(double budget_seconds, double warmup_seconds, double seconds_per_step);

// Checks a --minutes value: finite and > 0. Throws mipnerf::Error naming the value and what is accepted.
void check_budget_minutes(double minutes);

}  // namespace mipnerf::train
