// Training checkpoints: the file format, the trainer's keys, save, restore (resume) and load-for-render.
#include "train/checkpoint.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "core/error.hpp"
#include "train/model.hpp"

namespace mipnerf::train {
namespace fs = std::filesystem;
namespace {

// ---- The trainer's keys ----

constexpr const char* kFormat = "mipnerf-cl checkpoint";  // header "format": a training checkpoint
constexpr int kVersion = 1;

namespace key {
constexpr const char* format = "format";
constexpr const char* version = "version";
constexpr const char* step = "step";
constexpr const char* train_seconds = "train_seconds";
constexpr const char* config = "config";
constexpr const char* multiscale_data = "multiscale_data";
constexpr const char* device = "device";
constexpr const char* data = "data";
constexpr const char* adam_steps = "adam_steps";  // one per network, in order
}  // namespace key

std::string tensor_name(size_t network, const char* what) { return "network" + std::to_string(network) + "." + what; }

// Reads `path` and checks that the trainer wrote it.
io::CheckpointFile read_training_checkpoint(const std::string& path) {
  io::CheckpointFile c = io::read_checkpoint_file(path);
  if (c.header.value(key::format, "") != kFormat) throw Error(path + ": not a training checkpoint");
  return c;
}

CheckpointRecord record_of(const io::CheckpointFile& c) {
  CheckpointRecord r;
  r.step = c.header.at(key::step).get<int64_t>();
  r.train_seconds = c.header.value(key::train_seconds, 0.0);
  r.multiscale_data = c.header.value(key::multiscale_data, false);
  r.device = c.header.value(key::device, "");
  r.data_path = c.header.value(key::data, "");
  return r;
}

// Settings that may change between a run and its resume without changing what is learnt.
bool is_execution_setting(const std::string& difference) {
  const std::string name = difference.substr(0, difference.find(':'));
  for (const auto& s : settings()) {
    if (s.name == name) return s.group == "execution";
  }
  return false;
}

// Throws unless `saved` and `config` differ only in execution settings and the step count (logged).
void check_resumable(const TrainConfig& saved, const TrainConfig& config, const LogFn& log) {
  std::string mismatched;
  for (const auto& d : differences(saved, config)) {
    if (d.rfind("steps:", 0) == 0) {
      // Training longer (or shorter) is allowed: the schedule then spans the new step count from here on.
      if (log) {
        log(LogLevel::warning,
            "--resume with " + d + ": the learning-rate schedule now spans " + std::to_string(config.steps) + " steps");
      }
    } else if (!is_execution_setting(d)) {
      mismatched += (mismatched.empty() ? "" : "; ") + d;
    }
  }
  if (!mismatched.empty()) {
    throw Error("--resume: the settings differ from the checkpoint's (" + mismatched +
                "); run with the same "
                "settings, or start a new --out");
  }
}

}  // namespace

// ---- Where a run's checkpoints are ----

std::string checkpoint_path(const std::string& folder, int64_t step) {
  char name[64];
  std::snprintf(name, sizeof(name), "ckpt_%09lld.mnck", static_cast<long long>(step));
  return (fs::path(folder) / name).string();
}

std::vector<std::pair<int64_t, std::string>> list_checkpoints(const std::string& folder) {
  std::vector<std::pair<int64_t, std::string>> found;
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) return found;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() != 19 || name.rfind("ckpt_", 0) != 0 || name.substr(14) != ".mnck") continue;
    const std::string digits = name.substr(5, 9);
    if (!std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; })) continue;
    found.emplace_back(std::stoll(digits), entry.path().string());
  }
  std::sort(found.begin(), found.end());
  return found;
}

void prune_checkpoints(const std::string& folder, int keep) {
  auto all = list_checkpoints(folder);
  for (size_t i = 0; i + static_cast<size_t>(std::max(keep, 1)) < all.size(); ++i) {
    std::error_code ec;
    fs::remove(all[i].second, ec);
  }
}

std::string find_checkpoint(const std::string& path) {
  std::error_code ec;
  if (fs::is_regular_file(path, ec)) return path;
  for (const auto& folder : {(fs::path(path) / "checkpoints").string(), path}) {
    const auto found = list_checkpoints(folder);
    if (!found.empty()) return found.back().second;
  }
  throw Error(path + ": no checkpoint found (expected a .mnck file, or a training --out folder holding checkpoints/)");
}

VerifiedCheckpoint newest_verified_checkpoint(const std::string& folder) {
  VerifiedCheckpoint result;
  const auto all = list_checkpoints(folder);
  for (auto it = all.rbegin(); it != all.rend(); ++it) {
    try {
      io::read_checkpoint_file(it->second);
      result.path = it->second;
      result.step = it->first;
      return result;
    } catch (const Error& e) {
      std::error_code ec;
      fs::rename(it->second, it->second + ".corrupt", ec);
      result.skipped.push_back(std::string(e.what()) +
                               (ec ? "" : " (renamed to " + fs::path(it->second).filename().string() + ".corrupt)"));
    }
  }
  return result;
}

// ---- A training run's state ----

void save_training_checkpoint(const std::string& path, const TrainConfig& config, const CheckpointRecord& record,
                              const std::vector<std::unique_ptr<mlp::Mlp>>& networks,
                              const std::vector<std::unique_ptr<mlp::Adam>>& optimisers) {
  io::CheckpointFile c;
  c.header[key::format] = kFormat;
  c.header[key::version] = kVersion;
  c.header[key::step] = record.step;
  c.header[key::train_seconds] = record.train_seconds;
  c.header[key::config] = config_json(config);
  c.header[key::multiscale_data] = record.multiscale_data;
  c.header[key::device] = record.device;
  c.header[key::data] = record.data_path;
  nlohmann::json adam_steps = nlohmann::json::array();
  for (size_t i = 0; i < networks.size(); ++i) {
    c.add(tensor_name(i, "params"), networks[i]->download_params());
    mlp::AdamState state = optimisers[i]->state();
    adam_steps.push_back(state.step);
    c.add(tensor_name(i, "adam_m"), std::move(state.m));
    c.add(tensor_name(i, "adam_v"), std::move(state.v));
  }
  c.header[key::adam_steps] = adam_steps;
  io::write_checkpoint_file(path, c);
}

CheckpointRecord restore_training_checkpoint(const std::string& path, const TrainConfig& config,
                                             std::vector<std::unique_ptr<mlp::Mlp>>& networks,
                                             std::vector<std::unique_ptr<mlp::Adam>>& optimisers, const LogFn& log) {
  const io::CheckpointFile c = read_training_checkpoint(path);
  check_resumable(config_from_json(c.header.at(key::config), path), config, log);
  const auto& adam_steps = c.header.at(key::adam_steps);
  for (size_t i = 0; i < networks.size(); ++i) {
    networks[i]->upload_params(c.tensor(tensor_name(i, "params"), path));
    mlp::AdamState state;
    state.step = adam_steps.at(i).get<int64_t>();
    state.m = c.tensor(tensor_name(i, "adam_m"), path);
    state.v = c.tensor(tensor_name(i, "adam_v"), path);
    optimisers[i]->restore(state);
  }
  return record_of(c);
}

// ---- Trained networks, for rendering ----

std::vector<mlp::Mlp*> TrainedModel::network_pointers() const { return train::network_pointers(networks); }

TrainedModel load_trained_model(ocl::Context& ctx, const std::string& checkpoint_path) {
  const io::CheckpointFile c = read_training_checkpoint(checkpoint_path);
  const CheckpointRecord record = record_of(c);
  TrainedModel model;
  model.config = config_from_json(c.header.at(key::config), checkpoint_path);
  model.spec = make_graph_spec(model.config, record.multiscale_data);
  model.networks = make_networks(ctx, model.spec);
  for (size_t i = 0; i < model.networks.size(); ++i) {
    model.networks[i]->upload_params(c.tensor(tensor_name(i, "params"), checkpoint_path));
  }
  model.step = record.step;
  model.data_path = record.data_path;
  model.train_seconds = record.train_seconds;
  model.trained_on = record.device;
  return model;
}

}  // namespace mipnerf::train
