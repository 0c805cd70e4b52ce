// Checkpoint files: a JSON header and named float32 tensors in one file, written atomically and
// checked (magic, version, sizes, CRC-32 per tensor) when read back.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace mipnerf::io {

struct Checkpoint {
  nlohmann::json header = nlohmann::json::object();  // what the trainer records: step, configuration, ...
  std::vector<std::pair<std::string, std::vector<float>>> tensors;

  void add(const std::string& name, std::vector<float> values) { tensors.emplace_back(name, std::move(values)); }
  // The tensor called `name`; throws mipnerf::Error naming `where` (the file) when it is absent.
  const std::vector<float>& tensor(const std::string& name, const std::string& where) const;
};

// Layout: "MNCKPT01" (8 bytes), header length (uint64 LE), the header JSON (which also lists every
// tensor's name, element count and CRC-32), then each tensor's float32 values (LE) in order.
void write_checkpoint(const std::string& path, const Checkpoint& checkpoint);
// Throws mipnerf::Error naming the file and what is wrong: not a checkpoint, truncated, corrupted.
Checkpoint read_checkpoint(const std::string& path);

// Checkpoints of a run live in one folder as ckpt_<step, 9 digits>.mnck.
std::string checkpoint_path(const std::string& folder, int64_t step);
// (step, path) of every checkpoint in `folder`, by increasing step; empty when there is none.
std::vector<std::pair<int64_t, std::string>> list_checkpoints(const std::string& folder);
// Deletes all but the newest `keep` checkpoints.
void prune_checkpoints(const std::string& folder, int keep);

}  // namespace mipnerf::io
