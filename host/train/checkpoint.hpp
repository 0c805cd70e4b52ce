// Training checkpoints: the keys the trainer records in a checkpoint file (the format: io/checkpoint_file.hpp),
// where a run keeps them, saving and restoring a run (resume), and loading trained networks for rendering.
#pragma once

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "cl/context.hpp"
#include "core/log.hpp"
#include "graph/graph_spec.hpp"
#include "io/checkpoint_file.hpp"
#include "mlp/adam.hpp"
#include "mlp/grid_table.hpp"
#include "mlp/network.hpp"
#include "train/config.hpp"

namespace mipnerf::train {

// ---- Where a run's checkpoints are ----

// Checkpoints of a run live in one folder as ckpt_<step, 9 digits>.mnck.
std::string checkpoint_path(const std::string& folder, int64_t step);
// (step, path) of every checkpoint in `folder`, by increasing step; empty when there is none.
std::vector<std::pair<int64_t, std::string>> list_checkpoints(const std::string& folder);
// Deletes all but the newest `keep` checkpoints.
void prune_checkpoints(const std::string& folder, int keep);
// The checkpoint a path names: a .mnck file, or the newest in DIR/checkpoints or DIR.
std::string find_checkpoint(const std::string& path);

// The newest checkpoint in `folder` whose every byte verifies (io::read_checkpoint_file), for --resume. Each newer
// one that fails is renamed to "<name>.corrupt" (out of the listing, so pruning never keeps it over a good one, and
// kept for a look) and reported in `skipped` as "<path>: <reason>", newest first. `path` is empty when none verifies.
struct VerifiedCheckpoint {
  std::string path;
  int64_t step = 0;
  std::vector<std::string> skipped;
};
VerifiedCheckpoint newest_verified_checkpoint(const std::string& folder);

// ---- A training run's state ----

// What a training checkpoint records beside the configuration and the tensors.
struct CheckpointRecord {
  int64_t step = 0;              // steps completed
  double train_seconds = 0.0;    // training time up to this checkpoint, over every resume
  bool multiscale_data = false;  // the training split held several scales (decides the graph spec's area loss)
  std::string device;            // the device that trained it
  std::string data_path;         // the training data's folder or file (absolute); empty in older checkpoints
  std::string data_fingerprint;  // data::fingerprint of the training split; empty in older checkpoints
};

// What a training checkpoint's header holds, read without a device: the record, the configuration it was trained
// with, and the Adam step count of each network.
struct CheckpointHeader {
  CheckpointRecord record;
  TrainConfig config;
  std::vector<int64_t> adam_steps;       // [networks]
  std::vector<int64_t> grid_adam_steps;  // [grids] (Zip-NeRF)
};

// A run's grids and their optimisers (Zip-NeRF), saved and restored beside the networks: tensors grid<i>.params,
// grid<i>.adam_m, grid<i>.adam_v and the header's grid_adam_steps.
struct GridParts {
  std::vector<std::unique_ptr<mlp::GridTable>>* tables = nullptr;
  std::vector<std::unique_ptr<mlp::Adam>>* optimisers = nullptr;
  size_t size() const { return tables ? tables->size() : 0; }
};
// Reads the header of a parsed checkpoint file; throws mipnerf::Error naming `where` (the file) when it is not a
// training checkpoint's.
CheckpointHeader read_checkpoint_header(const io::CheckpointFile& checkpoint, const std::string& where);

// Writes `path`: the record, the configuration (a JSON object), and per network i the tensors
// network<i>.params, network<i>.adam_m, network<i>.adam_v with the Adam step counts.
void save_training_checkpoint(const std::string& path, const TrainConfig& config, const CheckpointRecord& record,
                              const std::vector<std::unique_ptr<mlp::Network>>& networks,
                              const std::vector<std::unique_ptr<mlp::Adam>>& optimisers, const GridParts& grids = {});

// The data a run resumes on: its path (for messages) and data::fingerprint of its training split.
struct TrainingData {
  std::string path;
  std::string fingerprint;
};

// Restores networks and optimisers from `path` exactly, and returns its record. The checkpoint's data must be `data`
// by content (its fingerprint, where the checkpoint records one) and its configuration must equal `config` except
// for execution settings and `steps` (logged as a warning through `log`); otherwise throws mipnerf::Error naming the
// data, or the differing settings.
CheckpointRecord restore_training_checkpoint(const std::string& path, const TrainConfig& config,
                                             const TrainingData& data,
                                             std::vector<std::unique_ptr<mlp::Network>>& networks,
                                             std::vector<std::unique_ptr<mlp::Adam>>& optimisers, const LogFn& log,
                                             const GridParts& grids = {});

// ---- Trained networks, for rendering ----

// The configuration a checkpoint was trained with, its graph spec (for `multiscale_data` as the training data had
// it) and the networks with their trained parameters.
struct TrainedModel {
  TrainConfig config;
  graph::GraphSpec spec;
  std::vector<std::unique_ptr<mlp::Network>> networks;
  std::vector<std::unique_ptr<mlp::GridTable>> grids;  // Zip-NeRF's; none for mip-NeRF
  int64_t step = 0;
  std::string data_path;     // the training data's folder or file (absolute); empty in older checkpoints
  double train_seconds = 0;  // training time up to this checkpoint
  std::string trained_on;    // the device that trained it
  std::vector<mlp::Network*> network_pointers() const;
  std::vector<mlp::GridTable*> grid_pointers() const;
};
// Throws mipnerf::Error naming the file when it is not a training checkpoint or does not fit its configuration. The
// networks run their products on `backend` (automatic: the device's choice, mlp::make_network).
TrainedModel load_trained_model(ocl::Context& ctx, const std::string& checkpoint_path,
                                gemm::GemmBackend backend = gemm::GemmBackend::automatic);

}  // namespace mipnerf::train
