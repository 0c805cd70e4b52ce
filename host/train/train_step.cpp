// One training step: batch, this rank's chunks, the sum over ranks, the gradient check, Adam.
#include "train/train_step.hpp"

#include <algorithm>

#include "graph/stage_traffic.hpp"
#include "parallel/world.hpp"
#include "train/data_parallel.hpp"

namespace mipnerf::train {

mlp::LrSchedule schedule_of(const TrainConfig& c) {
  mlp::LrSchedule s;
  s.lr_init = c.lr_init;
  s.lr_final = c.lr_final;
  s.max_steps = c.steps;
  s.warmup_steps = c.lr_warmup_steps;
  s.warmup_mult = c.lr_warmup_mult;
  return s;
}

namespace {

// Draws the step's batch; returns Σ lossmult over it (the batch size without the area loss).
double draw_batch(StepParts& p, int64_t step) {
  ocl::StageScope stage(p.ctx, "batch");
  ocl::add_stage_bytes(p.ctx, graph::traffic::batch(static_cast<size_t>(p.config.batch_size)));
  ops::batch_sample(p.ctx, p.data, {p.config.seed, p.config.batching}, static_cast<uint32_t>(step), p.batch);
  if (!p.spec.loss.multiscale) return static_cast<double>(p.config.batch_size);
  double sum = 0.0;
  for (float m : p.batch.lossmult.download(p.ctx)) sum += m;
  return sum;
}

// The fraction of training done at `step` (1-based) of `steps`, for proposal sampling's anneal: the official train.py's
// clip((step − 1)/(max_steps − 1), 0, 1); a one-step run is done at its step.
double train_fraction(int64_t step, int64_t steps) {
  if (steps <= 1) return 1.0;
  return std::clamp(static_cast<double>(step - 1) / static_cast<double>(steps - 1), 0.0, 1.0);
}

// This rank's contiguous share of the batch's ray indices, in chunks of up to chunk_rays: every rank draws the
// whole batch (cheap), so Σ lossmult stays global, and when the share is a multiple of the chunk each chunk is a
// single-process chunk bit for bit.
std::vector<ops::LevelLoss> forward_backward(StepParts& p, int64_t step, double lossmult_sum) {
  const size_t batch_rays = static_cast<size_t>(p.config.batch_size);
  const graph::RaySource source{p.data.cameras(), p.batch.camera_ids, p.batch.pixel_ids};
  const graph::TrainTargets targets{p.batch.target_rgb, p.spec.loss.multiscale ? &p.batch.lossmult : nullptr};
  const RayShare share = this_rank_rays(batch_rays);
  p.graph.set_train_fraction(train_fraction(step, p.config.steps));
  p.graph.begin_step(batch_rays, lossmult_sum);
  for (size_t first = share.first; first < share.end; first += p.chunk_rays) {
    p.graph.train_chunk(source, {first, std::min(p.chunk_rays, share.end - first)}, targets,
                        {p.config.seed, static_cast<uint32_t>(step)});
  }
  return p.graph.end_step();
}

}  // namespace

StepOutcome train_step(StepParts& p, int64_t step, const AfterBackward& after_backward,
                       std::vector<float>& reduce_buffer) {
  StepOutcome outcome;
  outcome.losses = forward_backward(p, step, draw_batch(p, step));
  if (after_backward) after_backward(step, p.networks);
  if (parallel::world().distributed()) {
    // Host work after end_step drained the queue: the gradients' copies to and from the host and the sums.
    ocl::StageScope reduce_stage(p.ctx, "allreduce (gradient copies + MPI)");
    ocl::HostTimer reduce_timer(p.ctx);
    sum_over_ranks(p.ctx, p.networks, outcome.losses, reduce_buffer);
  }
  bool finite = true;
  for (const auto& l : outcome.losses) finite = finite && l.finite();
  ocl::StageScope adam_stage(p.ctx, "adam");
  size_t parameters = 0;
  for (const auto& network : p.networks) parameters += network->params().size();
  for (const auto& grid : p.grids) parameters += grid->params().size();
  ocl::add_stage_bytes(p.ctx, graph::traffic::adam(parameters));
  std::vector<mlp::GradientStats> stats, grid_stats;
  for (size_t i = 0; i < p.networks.size(); ++i) {
    stats.push_back(p.optimisers[i]->gradient_stats(p.networks[i]->grads()));
    finite = finite && stats.back().finite();
  }
  for (size_t i = 0; i < p.grids.size(); ++i) {
    grid_stats.push_back(p.grid_optimisers[i]->gradient_stats(p.grids[i]->grads()));
    finite = finite && grid_stats.back().finite();
  }
  outcome.learning_rate = mlp::learning_rate(schedule_of(p.config), step);
  outcome.applied = finite;
  if (!finite) return outcome;
  for (size_t i = 0; i < p.networks.size(); ++i) {
    p.optimisers[i]->step(p.networks[i]->params(), p.networks[i]->grads(), outcome.learning_rate, &stats[i]);
  }
  for (size_t i = 0; i < p.grids.size(); ++i) {
    p.grid_optimisers[i]->step(p.grids[i]->params(), p.grids[i]->grads(), outcome.learning_rate, &grid_stats[i]);
  }
  return outcome;
}

}  // namespace mipnerf::train
