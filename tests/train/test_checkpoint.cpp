// Checkpoint files: exact round trip, and clear errors for truncated or corrupted files.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <cstring>
#include <iterator>
#include <limits>
#include <unistd.h>

#include "core/error.hpp"
#include "io/checkpoint.hpp"

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
  io::Checkpoint c;
  c.header["step"] = 1234;
  c.header["config"] = {{"batch_size", 4096}};
  c.add("params", {1.0f, -0.0f, std::numeric_limits<float>::denorm_min(), 3.4e38f, 1e-30f});
  c.add("empty", {});
  const auto path = io::checkpoint_path(dir.string(), 1234);
  io::write_checkpoint(path, c);
  const auto back = io::read_checkpoint(path);
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
  io::Checkpoint c;
  c.add("params", std::vector<float>(100, 0.5f));
  for (int64_t step : {10, 200, 30, 4000}) io::write_checkpoint(io::checkpoint_path(dir.string(), step), c);
  std::ofstream(dir / "ckpt_notanumber.mnck") << "x";
  auto listed = io::list_checkpoints(dir.string());
  REQUIRE(listed.size() == 4);
  CHECK(listed.front().first == 10);
  CHECK(listed.back().first == 4000);
  io::prune_checkpoints(dir.string(), 2);
  listed = io::list_checkpoints(dir.string());
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
  CHECK_THROWS_WITH_AS(io::read_checkpoint(path), doctest::Contains("truncated"), Error);
  std::string flipped = bytes;
  flipped[flipped.size() - 3] ^= 0x40;
  write(flipped);
  CHECK_THROWS_WITH_AS(io::read_checkpoint(path), doctest::Contains("CRC-32"), Error);
  write("not a checkpoint at all");
  CHECK_THROWS_WITH_AS(io::read_checkpoint(path), doctest::Contains("bad magic"), Error);
  CHECK_THROWS_WITH_AS(io::read_checkpoint((dir / "missing.mnck").string()), doctest::Contains("missing.mnck"), Error);
  fs::remove_all(dir);
}
