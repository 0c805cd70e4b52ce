// Training checkpoints: the file format, the trainer's keys, save, restore (resume) and load-for-render.
#include "train/checkpoint.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "core/error.hpp"
#include "io/json.hpp"
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
constexpr const char* data_fingerprint = "data_fingerprint";
constexpr const char* adam_steps = "adam_steps";  // one per network, in order
constexpr const char* grid_adam_steps = "grid_adam_steps";  // one per grid (Zip-NeRF), in order
}  // namespace key

std::string tensor_name(size_t network, const char* what) { return "network" + std::to_string(network) + "." + what; }
std::string grid_tensor_name(size_t grid, const char* what) { return "grid" + std::to_string(grid) + "." + what; }

// Typed reading of a header's keys: a missing key takes the default where there is one; a value of the wrong type
// (or a negative count) names the file and the key, instead of escaping as a JSON library exception.
class HeaderReader {
 public:
  HeaderReader(const nlohmann::json& header, const std::string& where) : header_(header), where_(where) {}

  const nlohmann::json* find(const char* key) const {
    if (!header_.is_object()) return nullptr;
    const auto it = header_.find(key);
    return it == header_.end() || it->is_null() ? nullptr : &*it;
  }
  const nlohmann::json& required(const char* key) const {
    const nlohmann::json* value = find(key);
    if (value == nullptr) throw Error(where_ + ": corrupt training checkpoint: its header has no '" + key + "'");
    return *value;
  }
  // A count (step, Adam steps): an integer from 0 to 2^63 - 1.
  int64_t count(const nlohmann::json& value, const std::string& what) const {
    if (value.is_number_unsigned() && value.get<uint64_t>() <= static_cast<uint64_t>(INT64_MAX)) {
      return static_cast<int64_t>(value.get<uint64_t>());
    }
    if (value.is_number_integer() && value.get<int64_t>() >= 0) return value.get<int64_t>();
    throw Error(where_ + ": corrupt training checkpoint: '" + what + "' must be a count (an integer >= 0), got " +
                value.dump());
  }
  double seconds(const char* key) const {
    const nlohmann::json* value = find(key);
    if (value == nullptr) return 0.0;
    if (!value->is_number() || !(value->get<double>() >= 0.0) || !std::isfinite(value->get<double>())) {
      throw Error(where_ + ": corrupt training checkpoint: '" + key + "' must be a number of seconds >= 0");
    }
    return value->get<double>();
  }
  bool flag(const char* key) const {
    const nlohmann::json* value = find(key);
    if (value != nullptr && !value->is_boolean()) {
      throw Error(where_ + ": corrupt training checkpoint: '" + key + "' must be true or false, got " +
                  io::json_type_name(*value));
    }
    return value != nullptr && value->get<bool>();
  }
  std::string text(const char* key) const {
    const nlohmann::json* value = find(key);
    if (value != nullptr && !value->is_string()) {
      throw Error(where_ + ": corrupt training checkpoint: '" + key + "' must be a string, got " +
                  io::json_type_name(*value));
    }
    return value != nullptr ? value->get<std::string>() : std::string();
  }

 private:
  const nlohmann::json& header_;
  const std::string& where_;
};

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

CheckpointHeader read_checkpoint_header(const io::CheckpointFile& c, const std::string& where) {
  const HeaderReader read(c.header, where);
  const nlohmann::json* format = read.find(key::format);
  if (format == nullptr || !format->is_string() || format->get<std::string>() != kFormat) {
    throw Error(where + ": not a training checkpoint (its header's '" + key::format + "' is not '" + kFormat + "')");
  }
  CheckpointHeader h;
  h.record.step = read.count(read.required(key::step), key::step);
  h.record.train_seconds = read.seconds(key::train_seconds);
  h.record.multiscale_data = read.flag(key::multiscale_data);
  h.record.device = read.text(key::device);
  h.record.data_path = read.text(key::data);
  h.record.data_fingerprint = read.text(key::data_fingerprint);
  h.config = config_from_json(read.required(key::config), where);
  // Only --resume needs the Adam steps (restore_training_checkpoint checks there is one per network).
  if (const nlohmann::json* steps = read.find(key::adam_steps)) {
    if (!steps->is_array()) throw Error(where + ": corrupt training checkpoint: '" + key::adam_steps + "' must be an array");
    for (const auto& step : *steps) h.adam_steps.push_back(read.count(step, key::adam_steps));
  }
  if (const nlohmann::json* steps = read.find(key::grid_adam_steps)) {
    if (!steps->is_array()) {
      throw Error(where + ": corrupt training checkpoint: '" + key::grid_adam_steps + "' must be an array");
    }
    for (const auto& step : *steps) h.grid_adam_steps.push_back(read.count(step, key::grid_adam_steps));
  }
  return h;
}

void save_training_checkpoint(const std::string& path, const TrainConfig& config, const CheckpointRecord& record,
                              const std::vector<std::unique_ptr<mlp::Network>>& networks,
                              const std::vector<std::unique_ptr<mlp::Adam>>& optimisers, const GridParts& grids) {
  io::CheckpointFile c;
  c.header[key::format] = kFormat;
  c.header[key::version] = kVersion;
  c.header[key::step] = record.step;
  c.header[key::train_seconds] = record.train_seconds;
  c.header[key::config] = config_json(config);
  c.header[key::multiscale_data] = record.multiscale_data;
  c.header[key::device] = record.device;
  c.header[key::data] = record.data_path;
  c.header[key::data_fingerprint] = record.data_fingerprint;
  nlohmann::json adam_steps = nlohmann::json::array();
  for (size_t i = 0; i < networks.size(); ++i) {
    c.add(tensor_name(i, "params"), networks[i]->download_params());
    mlp::AdamState state = optimisers[i]->state();
    adam_steps.push_back(state.step);
    c.add(tensor_name(i, "adam_m"), std::move(state.m));
    c.add(tensor_name(i, "adam_v"), std::move(state.v));
  }
  c.header[key::adam_steps] = adam_steps;
  if (grids.size() > 0) {
    nlohmann::json grid_steps = nlohmann::json::array();
    for (size_t i = 0; i < grids.size(); ++i) {
      c.add(grid_tensor_name(i, "params"), (*grids.tables)[i]->download_params());
      mlp::AdamState state = (*grids.optimisers)[i]->state();
      grid_steps.push_back(state.step);
      c.add(grid_tensor_name(i, "adam_m"), std::move(state.m));
      c.add(grid_tensor_name(i, "adam_v"), std::move(state.v));
    }
    c.header[key::grid_adam_steps] = grid_steps;
  }
  io::write_checkpoint_file(path, c);
}

CheckpointRecord restore_training_checkpoint(const std::string& path, const TrainConfig& config,
                                             const TrainingData& data,
                                             std::vector<std::unique_ptr<mlp::Network>>& networks,
                                             std::vector<std::unique_ptr<mlp::Adam>>& optimisers, const LogFn& log,
                                             const GridParts& grids) {
  const io::CheckpointFile c = io::read_checkpoint_file(path);
  const CheckpointHeader header = read_checkpoint_header(c, path);
  // The same training data, by content, before anything else is said (older checkpoints have no fingerprint: their
  // data is taken on trust).
  const CheckpointRecord& saved = header.record;
  if (!saved.data_fingerprint.empty() && saved.data_fingerprint != data.fingerprint) {
    throw Error("--resume: " + data.path + " is not the data this run trained on until step " +
                std::to_string(saved.step) + " (" + (saved.data_path.empty() ? "recorded in " + path : saved.data_path) +
                "): its training images or cameras differ; resume with the run's own data, or train into a new --out");
  }
  check_resumable(header.config, config, log);
  if (header.adam_steps.size() != networks.size()) {
    throw Error(path + ": corrupt training checkpoint: " + std::to_string(header.adam_steps.size()) +
                " Adam step counts for " + std::to_string(networks.size()) + " networks");
  }
  for (size_t i = 0; i < networks.size(); ++i) {
    networks[i]->upload_params(c.tensor(tensor_name(i, "params"), path));
    mlp::AdamState state;
    state.step = header.adam_steps[i];
    state.m = c.tensor(tensor_name(i, "adam_m"), path);
    state.v = c.tensor(tensor_name(i, "adam_v"), path);
    optimisers[i]->restore(state);
  }
  if (header.grid_adam_steps.size() != grids.size()) {
    throw Error(path + ": corrupt training checkpoint: " + std::to_string(header.grid_adam_steps.size()) +
                " grid Adam step counts for " + std::to_string(grids.size()) + " grids");
  }
  for (size_t i = 0; i < grids.size(); ++i) {
    (*grids.tables)[i]->upload_params(c.tensor(grid_tensor_name(i, "params"), path));
    mlp::AdamState state;
    state.step = header.grid_adam_steps[i];
    state.m = c.tensor(grid_tensor_name(i, "adam_m"), path);
    state.v = c.tensor(grid_tensor_name(i, "adam_v"), path);
    (*grids.optimisers)[i]->restore(state);
  }
  return header.record;
}

// ---- Trained networks, for rendering ----

std::vector<mlp::Network*> TrainedModel::network_pointers() const { return mlp::network_pointers(networks); }
std::vector<mlp::GridTable*> TrainedModel::grid_pointers() const { return mlp::grid_pointers(grids); }

TrainedModel load_trained_model(ocl::Context& ctx, const std::string& checkpoint_path, gemm::GemmBackend backend) {
  const io::CheckpointFile c = io::read_checkpoint_file(checkpoint_path);
  const CheckpointHeader header = read_checkpoint_header(c, checkpoint_path);
  const CheckpointRecord& record = header.record;
  TrainedModel model;
  model.config = header.config;
  model.spec = make_graph_spec(model.config, record.multiscale_data);
  model.networks = make_networks(ctx, model.spec, backend);
  for (size_t i = 0; i < model.networks.size(); ++i) {
    model.networks[i]->upload_params(c.tensor(tensor_name(i, "params"), checkpoint_path));
  }
  model.grids = make_grids(ctx, model.spec);
  for (size_t i = 0; i < model.grids.size(); ++i) {
    model.grids[i]->upload_params(c.tensor(grid_tensor_name(i, "params"), checkpoint_path));
  }
  model.step = record.step;
  model.data_path = record.data_path;
  model.train_seconds = record.train_seconds;
  model.trained_on = record.device;
  return model;
}

}  // namespace mipnerf::train
