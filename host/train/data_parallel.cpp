// The data-parallel glue of training: ray shares, rank agreement, sums over ranks.
#include "train/data_parallel.hpp"

#include <string>

#include "parallel/world.hpp"

namespace mipnerf::train {
namespace {

// What the ranks of a data-parallel run must share before the first step: the same settings (execution ones too:
// chunking decides which rays each rank trains), the same training data and the same parameters and Adam state.
uint64_t config_fingerprint(const TrainConfig& config) {
  const std::string text = to_json(config);
  return parallel::fnv1a(text.data(), text.size());
}

uint64_t data_fingerprint(const data::Split& split) {
  const std::vector<float> cameras = pack_cameras(split.cameras);
  uint64_t hash = parallel::fnv1a(cameras.data(), cameras.size() * sizeof(float));
  hash = parallel::fnv1a(split.scale_levels.data(), split.scale_levels.size() * sizeof(uint32_t), hash);
  return parallel::fnv1a(split.rgb.data(), split.rgb.size() * sizeof(float), hash);
}

uint64_t parameter_fingerprint(const std::vector<std::unique_ptr<mlp::Network>>& networks,
                               const std::vector<std::unique_ptr<mlp::Adam>>& optimisers) {
  uint64_t hash = parallel::fnv1a(nullptr, 0);
  for (size_t i = 0; i < networks.size(); ++i) {
    const std::vector<float> params = networks[i]->download_params();
    const mlp::AdamState state = optimisers[i]->state();
    hash = parallel::fnv1a(params.data(), params.size() * sizeof(float), hash);
    hash = parallel::fnv1a(state.m.data(), state.m.size() * sizeof(float), hash);
    hash = parallel::fnv1a(state.v.data(), state.v.size() * sizeof(float), hash);
    hash = parallel::fnv1a(&state.step, sizeof(state.step), hash);
  }
  return hash;
}

}  // namespace

void check_ranks_agree(const TrainConfig& config, const data::Split& train,
                       const std::vector<std::unique_ptr<mlp::Network>>& networks,
                       const std::vector<std::unique_ptr<mlp::Adam>>& optimisers) {
  if (!parallel::world().distributed()) return;
  parallel::require_same_on_every_rank(config_fingerprint(config), "the training settings",
                                       "start every rank with the same command line and --config file");
  parallel::require_same_on_every_rank(data_fingerprint(train), "the training data (cameras and pixels)",
                                       "give every rank the same --data, with identical files on every host");
  parallel::require_same_on_every_rank(parameter_fingerprint(networks, optimisers), "the parameters and Adam state",
                                       "every rank must see the same --out folder (a shared filesystem), so that "
                                       "--resume reads the same checkpoint everywhere");
}

void sum_over_ranks(ocl::Context& ctx, std::vector<std::unique_ptr<mlp::Network>>& networks,
                    std::vector<ops::LevelLoss>& losses, std::vector<float>& flat) {
  size_t total = 0;
  for (const auto& network : networks) total += network->parameter_count();
  flat.resize(total);
  size_t at = 0;
  for (auto& network : networks) {
    network->grads().download(ctx, flat.data() + at, network->parameter_count());
    at += network->parameter_count();
  }
  parallel::world().sum_in_place(flat.data(), flat.size());
  at = 0;
  for (auto& network : networks) {
    network->grads().upload(ctx, flat.data() + at, network->parameter_count());
    at += network->parameter_count();
  }
  std::vector<double> sums;
  for (const auto& l : losses) {
    sums.push_back(l.weighted_sse);
    sums.push_back(l.plain_sse);
    sums.push_back(l.interlevel);  // a proposal round's: each rank's share of the batch-normalised loss
    sums.push_back(l.distortion);  // likewise
  }
  parallel::world().sum_in_place(sums.data(), sums.size());
  for (size_t i = 0; i < losses.size(); ++i) {
    losses[i].weighted_sse = sums[4 * i];
    losses[i].plain_sse = sums[4 * i + 1];
    losses[i].interlevel = sums[4 * i + 2];
    losses[i].distortion = sums[4 * i + 3];
  }
}

bool any_rank(bool flag) {
  double value = flag ? 1.0 : 0.0;
  parallel::world().sum_in_place(&value, 1);
  return value > 0.0;
}

RayShare this_rank_rays(size_t batch_rays) {
  const parallel::World& world = parallel::world();
  const std::vector<size_t> shares = parallel::share_offsets(batch_rays, world.size());
  return {shares[static_cast<size_t>(world.rank())], shares[static_cast<size_t>(world.rank()) + 1]};
}

}  // namespace mipnerf::train
