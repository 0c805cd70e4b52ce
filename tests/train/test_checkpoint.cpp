// Checkpoints (train/checkpoint.hpp): the file's exact round trip and clear errors for truncated or corrupted files;
// the trainer's keys, save, restore and load-for-render, against a version-1 file written byte by byte.
#include <doctest/doctest.h>
#include <zlib.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <cstring>
#include <iterator>
#include <limits>
#include <map>
#include <unistd.h>

#include "core/error.hpp"
#include "mlp/mlp_config.hpp"
#include "support/test_context.hpp"
#include "train/checkpoint.hpp"
#include "train/model.hpp"

using namespace mipnerf;
namespace fs = std::filesystem;

namespace {
fs::path fresh_dir(const std::string& name) {
  const auto dir = fs::temp_directory_path() / ("mipnerf-test-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}
}  // namespace

TEST_CASE("checkpoint: header and tensors round-trip bit for bit") {
  const auto dir = fresh_dir("ckpt");
  train::CheckpointFile c;
  c.header["step"] = 1234;
  c.header["config"] = {{"batch_size", 4096}};
  c.add("params", {1.0f, -0.0f, std::numeric_limits<float>::denorm_min(), 3.4e38f, 1e-30f});
  c.add("empty", {});
  const auto path = train::checkpoint_path(dir.string(), 1234);
  train::write_checkpoint_file(path, c);
  const auto back = train::read_checkpoint_file(path);
  CHECK(back.header["step"] == 1234);
  CHECK(back.header["config"]["batch_size"] == 4096);
  CHECK(!back.header.contains("tensors"));
  const auto& p = back.tensor("params", path);
  REQUIRE(p.size() == 5);
  for (size_t i = 0; i < p.size(); ++i) CHECK(std::memcmp(&p[i], &c.tensors[0].second[i], sizeof(float)) == 0);
  CHECK(std::signbit(p[1]));
  CHECK(back.tensor("empty", path).empty());
  CHECK_THROWS_WITH_AS(back.tensor("adam_m", path), doctest::Contains("adam_m"), Error);
  fs::remove_all(dir);
}

TEST_CASE("checkpoint: listing, pruning, and errors for damaged files") {
  const auto dir = fresh_dir("ckpt-list");
  train::CheckpointFile c;
  c.add("params", std::vector<float>(100, 0.5f));
  for (int64_t step : {10, 200, 30, 4000}) train::write_checkpoint_file(train::checkpoint_path(dir.string(), step), c);
  std::ofstream(dir / "ckpt_notanumber.mnck") << "x";
  auto listed = train::list_checkpoints(dir.string());
  REQUIRE(listed.size() == 4);
  CHECK(listed.front().first == 10);
  CHECK(listed.back().first == 4000);
  train::prune_checkpoints(dir.string(), 2);
  listed = train::list_checkpoints(dir.string());
  REQUIRE(listed.size() == 2);
  CHECK(listed[0].first == 200);

  const std::string path = listed[1].second;
  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  auto write = [&](const std::string& b) { std::ofstream(path, std::ios::binary | std::ios::trunc) << b; };
  write(bytes.substr(0, bytes.size() - 4));
  CHECK_THROWS_WITH_AS(train::read_checkpoint_file(path), doctest::Contains("truncated"), Error);
  std::string flipped = bytes;
  flipped[flipped.size() - 3] ^= 0x40;
  write(flipped);
  CHECK_THROWS_WITH_AS(train::read_checkpoint_file(path), doctest::Contains("CRC-32"), Error);
  write("not a checkpoint at all");
  CHECK_THROWS_WITH_AS(train::read_checkpoint_file(path), doctest::Contains("bad magic"), Error);
  CHECK_THROWS_WITH_AS(train::read_checkpoint_file((dir / "missing.mnck").string()), doctest::Contains("missing.mnck"),
                       Error);
  fs::remove_all(dir);
}

// ---- The trainer's checkpoints: keys, save, restore, load for rendering ----

namespace {

// The tiny preset at a width that builds in milliseconds.
train::TrainConfig small_config(std::map<std::string, std::string> extra = {}) {
  extra.emplace("mlp_width", "8");
  extra.emplace("view_branch_width", "4");
  extra.emplace("pos_max_deg", "2");
  return train::resolve_config("tiny", "mipnerf", extra);
}

std::vector<float> ramp(size_t n, float start, float step) {
  std::vector<float> values(n);
  for (size_t i = 0; i < n; ++i) values[i] = start + step * static_cast<float>(i);
  return values;
}

void append_u64_le(std::string& out, uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

uint32_t crc_of(const std::vector<float>& values) {
  return static_cast<uint32_t>(crc32(0L, reinterpret_cast<const Bytef*>(values.data()),
                                     static_cast<uInt>(values.size() * sizeof(float))));
}

// A version-1 training checkpoint built byte by byte, as the trainer has written them from the start (the
// configuration parsed from its JSON text), so a change of the on-disk format fails here.
void write_version1_checkpoint(const std::string& path, const train::TrainConfig& config,
                               const std::vector<std::pair<std::string, std::vector<float>>>& tensors) {
  nlohmann::json header = {{"format", "mipnerf-cl checkpoint"},
                           {"version", 1},
                           {"step", 7},
                           {"train_seconds", 1.5},
                           {"config", nlohmann::json::parse(train::to_json(config))},
                           {"multiscale_data", false},
                           {"device", "the test device"},
                           {"data", "/nowhere/scene"},
                           {"adam_steps", {7}},
                           {"tensors", nlohmann::json::array()}};
  for (const auto& [name, values] : tensors) {
    header["tensors"].push_back({{"name", name}, {"count", values.size()}, {"crc32", crc_of(values)}});
  }
  const std::string text = header.dump();
  std::string bytes = "MNCKPT01";
  append_u64_le(bytes, text.size());
  bytes += text;
  for (const auto& [name, values] : tensors) {
    bytes.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(float));
  }
  std::ofstream(path, std::ios::binary) << bytes;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

}  // namespace

TEST_CASE("checkpoint: a version-1 file written byte by byte loads for rendering and resumes") {
  auto& ctx = test::test_context();
  const auto dir = fresh_dir("ckpt-v1");
  const auto config = small_config();
  const graph::GraphSpec spec = train::make_graph_spec(config, false);
  REQUIRE(spec.mlps.size() == 1);
  const size_t n = mlp::parameter_layout(spec.mlps[0]).total;
  const auto params = ramp(n, -0.5f, 1e-4f), adam_m = ramp(n, 0.25f, -1e-5f), adam_v = ramp(n, 1e-3f, 1e-6f);
  const std::string path = train::checkpoint_path(dir.string(), 7);
  write_version1_checkpoint(path, config,
                            {{"network0.params", params}, {"network0.adam_m", adam_m}, {"network0.adam_v", adam_v}});

  const train::TrainedModel model = train::load_trained_model(ctx, train::find_checkpoint(dir.string()));
  CHECK(model.step == 7);
  CHECK(model.train_seconds == 1.5);
  CHECK(model.trained_on == "the test device");
  CHECK(model.data_path == "/nowhere/scene");
  CHECK(train::differences(model.config, config).empty());
  REQUIRE(model.networks.size() == 1);
  CHECK(same_bits(model.networks[0]->download_params(), params));

  auto networks = train::make_networks(ctx, spec);
  std::vector<std::unique_ptr<mlp::Adam>> optimisers;
  optimisers.push_back(std::make_unique<mlp::Adam>(ctx, n));
  std::vector<std::string> warnings;
  const LogFn log = [&](LogLevel, const std::string& message) { warnings.push_back(message); };
  const auto record = train::restore_training_checkpoint(path, small_config({{"steps", "900"}, {"chunk_rays", "64"}}),
                                                         networks, optimisers, log);
  CHECK(record.step == 7);
  CHECK(record.device == "the test device");
  REQUIRE(warnings.size() == 1);  // a longer run is allowed, with a word about the schedule; chunk_rays is silent
  CHECK(warnings[0].find("steps: 300 -> 900") != std::string::npos);
  CHECK(same_bits(networks[0]->download_params(), params));
  const mlp::AdamState state = optimisers[0]->state();
  CHECK(state.step == 7);
  CHECK(same_bits(state.m, adam_m));
  CHECK(same_bits(state.v, adam_v));
  CHECK_THROWS_WITH_AS(
      train::restore_training_checkpoint(path, small_config({{"lr_init", "1e-3"}}), networks, optimisers, log),
      doctest::Contains("lr_init"), Error);
  fs::remove_all(dir);
}

TEST_CASE("checkpoint: save records the configuration as a JSON object beside the step, device and data") {
  auto& ctx = test::test_context();
  const auto dir = fresh_dir("ckpt-save");
  const auto config = small_config();
  const graph::GraphSpec spec = train::make_graph_spec(config, false);
  const auto networks = train::make_networks(ctx, spec);
  std::vector<std::unique_ptr<mlp::Adam>> optimisers;
  optimisers.push_back(std::make_unique<mlp::Adam>(ctx, networks[0]->parameter_count()));
  train::CheckpointRecord record;
  record.step = 12;
  record.train_seconds = 3.25;
  record.multiscale_data = true;
  record.device = "dev";
  record.data_path = "/data/scene";
  const std::string path = train::checkpoint_path(dir.string(), 12);
  train::save_training_checkpoint(path, config, record, networks, optimisers);

  const auto file = train::read_checkpoint_file(path);
  std::vector<std::string> keys;
  for (const auto& item : file.header.items()) keys.push_back(item.key());
  CHECK(keys == std::vector<std::string>{"adam_steps", "config", "data", "device", "format", "multiscale_data", "step",
                                         "train_seconds", "version"});
  CHECK(file.header["format"] == "mipnerf-cl checkpoint");
  CHECK(file.header["version"] == 1);
  REQUIRE(file.header["config"].is_object());
  CHECK(file.header["config"]["mlp_width"] == 8);
  CHECK(file.header["config"]["variant"] == "mipnerf");
  CHECK(file.header["adam_steps"] == nlohmann::json::array({0}));
  REQUIRE(file.tensors.size() == 3);
  CHECK(file.tensors[0].first == "network0.params");
  CHECK(file.tensors[1].first == "network0.adam_m");
  CHECK(file.tensors[2].first == "network0.adam_v");
  CHECK(same_bits(file.tensors[0].second, networks[0]->download_params()));

  const auto model = train::load_trained_model(ctx, path);
  CHECK(model.step == 12);
  REQUIRE(config.area_loss);
  CHECK(model.spec.loss.multiscale);  // multiscale_data came back: the area loss is compiled in
  // A checkpoint file that the trainer did not write is refused by name.
  train::CheckpointFile other;
  other.add("params", {1.0f});
  const std::string other_path = (dir / "other.mnck").string();
  train::write_checkpoint_file(other_path, other);
  CHECK_THROWS_WITH_AS(train::load_trained_model(ctx, other_path), doctest::Contains("not a training checkpoint"),
                       Error);
  CHECK_THROWS_WITH_AS(train::find_checkpoint((dir / "empty").string()), doctest::Contains("no checkpoint found"),
                       Error);
  fs::remove_all(dir);
}
