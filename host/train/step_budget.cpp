// The step count of a wall-clock budget (train --minutes): the warm-up's rule and the arithmetic.
#include "train/step_budget.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/error.hpp"

namespace mipnerf::train {

double warmup_target_seconds(double budget_seconds) { return std::min(10.0, 0.02 * budget_seconds); }

bool warmup_done(int64_t warm_steps, double warm_seconds, double budget_seconds) {
  if (warm_steps >= kMaxWarmSteps) return true;
  return warm_steps >= kMinWarmSteps && warm_seconds >= warmup_target_seconds(budget_seconds);
}

int64_t steps_for_budget(double budget_seconds, double warmup_seconds, double seconds_per_step) {
  if (!(seconds_per_step > 0.0) || !std::isfinite(seconds_per_step)) {
    throw Error("the warm-up measured " + std::to_string(seconds_per_step) +
                " s per step, which cannot size a budget (a clock that did not advance?)");
  }
  const double left = budget_seconds - warmup_seconds;
  const double steps = std::floor(left / seconds_per_step);
  if (!(steps >= 1.0)) {
    char message[320];
    std::snprintf(message, sizeof(message),
                  "--minutes %.3g: the warm-up took %.1f s of the %.1f s budget and a step takes %.3f s, so not one "
                  "step fits; give at least --minutes %.2g",
                  budget_seconds / 60.0, warmup_seconds, budget_seconds, seconds_per_step,
                  std::ceil((warmup_seconds + 10.0 * seconds_per_step) / 60.0 * 100.0) / 100.0);
    throw Error(message);
  }
  return static_cast<int64_t>(steps);
}

void check_budget_minutes(double minutes) {
  if (!(minutes > 0.0) || !std::isfinite(minutes)) {
    char message[200];
    std::snprintf(message, sizeof(message),
                  "--minutes %g: the training budget must be a positive number of minutes (e.g. --minutes 5 or "
                  "--minutes 0.5)",
                  minutes);
    throw Error(message);
  }
}

std::string StepBudget::describe() const {
  char line[400];
  std::snprintf(line, sizeof(line),
                "time budget %.4g min: warm-up of 1 cold step (%.2f s) and %lld timed steps (%.2f s) measured %.4f "
                "s/step; %lld steps fill the %.1f s left (the learning-rate schedule spans them)",
                budget_seconds / 60.0, cold_step_seconds, static_cast<long long>(warm_steps), warm_seconds,
                seconds_per_step, static_cast<long long>(steps), budget_seconds - warmup_seconds());
  return line;
}

nlohmann::ordered_json StepBudget::to_json() const {
  nlohmann::ordered_json j;
  j["budget_seconds"] = budget_seconds;
  j["cold_step_seconds"] = cold_step_seconds;
  j["warm_steps"] = warm_steps;
  j["warm_seconds"] = warm_seconds;
  j["seconds_per_step"] = seconds_per_step;
  j["warmup_seconds"] = warmup_seconds();
  j["steps"] = steps;
  j["note"] = "the warm-up's steps were discarded (networks and Adam reset) and its time counted in train_seconds";
  return j;
}

}  // namespace mipnerf::train
