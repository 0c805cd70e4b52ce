// Checkpoints (io/checkpoint_file.hpp, train/checkpoint.hpp): the file's exact round trip, every changed byte and
// every cut found; the trainer's keys, save, restore and load-for-render, against a format-1 file written byte by
// byte (the format before the whole-file checksum, still read).
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
  io::CheckpointFile c;
  c.header["step"] = 1234;
  c.header["config"] = {{"batch_size", 4096}};
  c.add("params", {1.0f, -0.0f, std::numeric_limits<float>::denorm_min(), 3.4e38f, 1e-30f});
  c.add("empty", {});
  const auto path = train::checkpoint_path(dir.string(), 1234);
  io::write_checkpoint_file(path, c);
  const auto back = io::read_checkpoint_file(path);
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
  io::CheckpointFile c;
  c.add("params", std::vector<float>(100, 0.5f));
  for (int64_t step : {10, 200, 30, 4000}) io::write_checkpoint_file(train::checkpoint_path(dir.string(), step), c);
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
  CHECK_THROWS_WITH_AS(io::read_checkpoint_file(path), doctest::Contains("truncated"), Error);
  std::string flipped = bytes;
  flipped[flipped.size() - 7] ^= 0x40;
  write(flipped);
  CHECK_THROWS_WITH_AS(io::read_checkpoint_file(path), doctest::Contains("corrupt checkpoint: its CRC-32"), Error);
  write("not a checkpoint at all");
  CHECK_THROWS_WITH_AS(io::read_checkpoint_file(path), doctest::Contains("not a mipnerf-cl checkpoint"), Error);
  CHECK_THROWS_WITH_AS(io::read_checkpoint_file((dir / "missing.mnck").string()), doctest::Contains("missing.mnck"),
                       Error);
  fs::remove_all(dir);
}

TEST_CASE("checkpoint: one changed byte anywhere in the file, or a cut anywhere, is refused as corrupt by name") {
  io::CheckpointFile c;
  c.header["step"] = 42;
  c.header["config"] = {{"mlp_width", 8}};
  c.add("params", {1.0f, 2.0f, -3.0f});
  c.add("adam_m", {0.5f});
  const std::string bytes = io::checkpoint_bytes(c);
  REQUIRE(io::parse_checkpoint(bytes, "good.mnck").tensor("params", "good.mnck").size() == 3);
  // Every byte: the magic, both lengths, the header's JSON text (names, counts, step), the floats, the CRC itself;
  // each flipped bit by bit and set to zero.
  int refused = 0, tried = 0;
  for (size_t at = 0; at < bytes.size(); ++at) {
    for (int change = 0; change < 9; ++change) {
      std::string damaged = bytes;
      damaged[at] = change < 8 ? static_cast<char>(damaged[at] ^ (1 << change)) : '\0';
      if (damaged == bytes) continue;
      ++tried;
      try {
        io::parse_checkpoint(damaged, "damaged.mnck");
        FAIL_CHECK("byte " << at << " change " << change << " was not noticed");
      } catch (const Error& e) {
        const std::string message = e.what();
        if (message.rfind("damaged.mnck: ", 0) == 0 && message.find("corrupt") != std::string::npos) ++refused;
        else FAIL_CHECK("byte " << at << ": " << message);
      }
    }
  }
  CHECK(refused == tried);
  CHECK(tried > 8 * static_cast<int>(bytes.size()));
  for (size_t length = 0; length < bytes.size(); ++length) {
    CHECK_THROWS_AS(io::parse_checkpoint(bytes.substr(0, length), "cut.mnck"), Error);
  }
  CHECK_THROWS_WITH_AS(io::parse_checkpoint(bytes + "x", "long.mnck"), doctest::Contains("corrupt"), Error);
  // A preamble claiming a header of 2^64 - 1 bytes (with a matching CRC: a writer's bug, not damage) is refused
  // without allocating.
  std::string huge = bytes.substr(0, bytes.size() - 4);
  for (int i = 16; i < 24; ++i) huge[i] = static_cast<char>(0xff);
  const uint32_t crc = static_cast<uint32_t>(crc32(0L, reinterpret_cast<const Bytef*>(huge.data()), huge.size()));
  for (int i = 0; i < 4; ++i) huge.push_back(static_cast<char>((crc >> (8 * i)) & 0xff));
  CHECK_THROWS_WITH_AS(io::parse_checkpoint(huge, "huge.mnck"), doctest::Contains("header runs past the end"), Error);
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

// A format-1 training checkpoint built byte by byte, as the trainer wrote them before format 2 (the
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

  auto networks = train::make_networks(ctx, spec, gemm::GemmBackend::automatic);
  std::vector<std::unique_ptr<mlp::Adam>> optimisers;
  optimisers.push_back(std::make_unique<mlp::Adam>(ctx, n));
  std::vector<std::string> warnings;
  const LogFn log = [&](LogLevel, const std::string& message) { warnings.push_back(message); };
  // A version-1 checkpoint records no data fingerprint: any data is taken on trust.
  const train::TrainingData any_data{"/elsewhere/scene", "fnv1a64:0123456789abcdef"};
  const auto record = train::restore_training_checkpoint(path, small_config({{"steps", "900"}, {"chunk_rays", "64"}}),
                                                         any_data, networks, optimisers, log);
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
      train::restore_training_checkpoint(path, small_config({{"lr_init", "1e-3"}}), any_data, networks, optimisers, log),
      doctest::Contains("lr_init"), Error);
  fs::remove_all(dir);
}

TEST_CASE("checkpoint: save records the configuration as a JSON object beside the step, device and data") {
  auto& ctx = test::test_context();
  const auto dir = fresh_dir("ckpt-save");
  const auto config = small_config();
  const graph::GraphSpec spec = train::make_graph_spec(config, false);
  auto networks = train::make_networks(ctx, spec, gemm::GemmBackend::automatic);
  std::vector<std::unique_ptr<mlp::Adam>> optimisers;
  optimisers.push_back(std::make_unique<mlp::Adam>(ctx, networks[0]->parameter_count()));
  train::CheckpointRecord record;
  record.step = 12;
  record.train_seconds = 3.25;
  record.multiscale_data = true;
  record.device = "dev";
  record.data_path = "/data/scene";
  record.data_fingerprint = "fnv1a64:00000000deadbeef";
  const std::string path = train::checkpoint_path(dir.string(), 12);
  train::save_training_checkpoint(path, config, record, networks, optimisers);

  const auto file = io::read_checkpoint_file(path);
  std::vector<std::string> keys;
  for (const auto& item : file.header.items()) keys.push_back(item.key());
  CHECK(keys == std::vector<std::string>{"adam_steps", "config", "data", "data_fingerprint", "device", "format",
                                         "multiscale_data", "step", "train_seconds", "version"});
  CHECK(file.header["data_fingerprint"] == "fnv1a64:00000000deadbeef");
  // Restoring onto other data (by content) is refused first, naming both; onto the same, it restores.
  CHECK_THROWS_WITH_AS(train::restore_training_checkpoint(path, config, {"/data/other", "fnv1a64:0000000000000001"},
                                                          networks, optimisers, {}),
                       doctest::Contains("--resume: /data/other is not the data this run trained on until step 12 "
                                         "(/data/scene): its training images or cameras differ"),
                       Error);
  CHECK(train::restore_training_checkpoint(path, config, {"/data/moved", "fnv1a64:00000000deadbeef"}, networks,
                                           optimisers, {})
            .step == 12);
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
  io::CheckpointFile other;
  other.add("params", {1.0f});
  const std::string other_path = (dir / "other.mnck").string();
  io::write_checkpoint_file(other_path, other);
  CHECK_THROWS_WITH_AS(train::load_trained_model(ctx, other_path), doctest::Contains("not a training checkpoint"),
                       Error);
  CHECK_THROWS_WITH_AS(train::find_checkpoint((dir / "empty").string()), doctest::Contains("no checkpoint found"),
                       Error);
  fs::remove_all(dir);
}

TEST_CASE("checkpoint: a header with a missing or mistyped key is refused naming the file and the key") {
  // A training header as save_training_checkpoint writes it, then one key at a time broken (found by fuzzing: these
  // escaped as JSON library exceptions, and an invalid configuration did not name the file).
  const auto valid = [] {
    io::CheckpointFile c;
    c.header = {{"format", "mipnerf-cl checkpoint"}, {"version", 1}, {"step", 7},
                {"config", train::config_json(train::resolve_config("tiny", "mipnerf", {}))},
                {"multiscale_data", false}, {"device", "cpu"}, {"data", "/scene"}, {"adam_steps", {7}}};
    return c;
  };
  const auto header = train::read_checkpoint_header(valid(), "a.mnck");
  CHECK(header.record.step == 7);
  CHECK(header.record.data_path == "/scene");
  CHECK(header.adam_steps == std::vector<int64_t>{7});
  auto broken = [&](const char* key, nlohmann::json value, const char* expected) {
    io::CheckpointFile c = valid();
    if (value.is_null()) c.header.erase(key);
    else c.header[key] = value;
    CAPTURE(key);
    CHECK_THROWS_WITH_AS(train::read_checkpoint_header(c, "a.mnck"), doctest::Contains(expected), Error);
  };
  broken("format", 3, "a.mnck: not a training checkpoint");
  broken("step", nullptr, "a.mnck: corrupt training checkpoint: its header has no 'step'");
  broken("step", "7", "a.mnck: corrupt training checkpoint: 'step' must be a count");
  broken("step", -1, "'step' must be a count");
  broken("train_seconds", "long", "a.mnck: corrupt training checkpoint: 'train_seconds' must be a number");
  broken("multiscale_data", 1, "'multiscale_data' must be true or false");
  broken("device", 2, "'device' must be a string");
  broken("adam_steps", 5, "'adam_steps' must be an array");
  broken("adam_steps", {1, "x"}, "'adam_steps' must be a count");
  broken("config", nullptr, "its header has no 'config'");
  nlohmann::json bad_config = valid().header["config"];
  bad_config["max_bad_steps"] = 0;
  broken("config", bad_config, "a.mnck: invalid configuration: max_bad_steps must be at least 1");
  // Rendering needs no Adam steps; a header without them still loads (resume checks one per network).
  io::CheckpointFile without = valid();
  without.header.erase("adam_steps");
  CHECK(train::read_checkpoint_header(without, "a.mnck").adam_steps.empty());
}
