// The data-parallel glue of training under mpirun (over host/dist): which rays of a batch this rank trains, the
// checks that every rank starts from the same settings, data and parameters, and the sums over ranks a step needs.
// Without MPI (one rank) each is a no-op or the whole batch.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "cl/context.hpp"
#include "data/dataset.hpp"
#include "mlp/adam.hpp"
#include "mlp/network.hpp"
#include "ops/loss.hpp"
#include "train/config.hpp"

namespace mipnerf::train {

// This rank's contiguous share [first, end) of a batch's ray indices (every rank has work when batch >= ranks).
struct RayShare {
  size_t first = 0, end = 0;
};
RayShare this_rank_rays(size_t batch_rays);

// Under mpirun: every rank checks it has rank 0's settings, data and parameters (at the start and after a resume),
// and all stop with one message otherwise.
void check_ranks_agree(const TrainConfig& config, const data::Split& train,
                       const std::vector<std::unique_ptr<mlp::Network>>& networks,
                       const std::vector<std::unique_ptr<mlp::Adam>>& optimisers);

// The gradients of every network and the step's loss sums, summed over the ranks (one MPI_Allreduce of floats,
// one of doubles). Each rank's gradients cover its share of the batch and are already divided by the batch's
// global Σ lossmult (graph begin_step), so their sum is the single-process gradient, up to summation order.
// `buffer` is reused between steps.
void sum_over_ranks(ocl::Context& ctx, std::vector<std::unique_ptr<mlp::Network>>& networks,
                    std::vector<ops::LevelLoss>& losses, std::vector<float>& buffer);

// True on every rank when any rank asks to stop (Ctrl-C, SIGTERM): all stop after the same step.
bool any_rank(bool flag);

}  // namespace mipnerf::train
