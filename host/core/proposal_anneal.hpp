// The per-step constants of proposal sampling: the anneal exponent (Schlick's bias function of the training fraction)
// and each round's random key.
#pragma once

#include <cstddef>

#include "core/stage_options.hpp"

namespace mipnerf {

// Zip-NeRF's weight annealing (official camp_zipnerf models.py Model.__call__, Schlick's bias, arXiv 2010.09714):
// anneal = bias(train_frac, s) = s·x / ((s − 1)·x + 1) with x = train_frac in [0, 1], for anneal_slope s > 0, and 1
// when s ≤ 0 (the official turns annealing off). It rises from 0 at x = 0 (uniform sampling over the non-empty
// intervals) to 1 at x = 1 (the weights as they are); s = 10 (official default) reaches 0.5 at x = 1/11.
// The result is SampleIntervalsOptions::anneal.
inline double proposal_anneal(double train_frac, double anneal_slope) {
  if (!(anneal_slope > 0.0)) return 1.0;
  return (anneal_slope * train_frac) / ((anneal_slope - 1.0) * train_frac + 1.0);
}

// The key proposal-sampled level `level` draws its jitter with (official: a fresh random_split key per level): the
// step's key with its seed offset by the level (the kernel's counter holds ray, step and sample; the seed is the one
// free part).
inline RngKey proposal_round_key(const RngKey& step_key, size_t level) {
  return {step_key.seed + 0x9E3779B97F4A7C15ull * level, step_key.step, step_key.first_ray};
}

}  // namespace mipnerf
