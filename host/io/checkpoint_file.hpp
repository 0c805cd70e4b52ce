// The checkpoint file: a JSON header and named float32 tensors, every byte covered by one CRC-32 that is checked
// before anything in the file is used. What the trainer stores in it: train/checkpoint.hpp.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace mipnerf::io {

struct CheckpointFile {
  nlohmann::json header = nlohmann::json::object();  // what the writer records: step, configuration, ...
  std::vector<std::pair<std::string, std::vector<float>>> tensors;

  void add(const std::string& name, std::vector<float> values) { tensors.emplace_back(name, std::move(values)); }
  // The tensor called `name`; throws mipnerf::Error naming `where` (the file) when it is absent.
  const std::vector<float>& tensor(const std::string& name, const std::string& where) const;
};

// Format 2, all integers little-endian:
//   "MNCKPT02" | file bytes (uint64) | header bytes (uint64) | header JSON | tensors (float32) | CRC-32 (uint32)
// The header lists every tensor's name and element count, in file order. The CRC-32 covers every byte before it,
// so one changed byte anywhere (magic, lengths, header, tensors) is found before the header is parsed.
// Format 1 ("MNCKPT01", written before the whole-file checksum: magic | header bytes | header | tensors, a CRC-32
// per tensor in the header, the header itself unchecked) is still read, so older runs keep rendering.
std::string checkpoint_bytes(const CheckpointFile& checkpoint);
// Throws mipnerf::Error "<where>: ..." saying it is corrupt (or not a checkpoint, or truncated) on any damage.
CheckpointFile parse_checkpoint(std::string_view bytes, const std::string& where);

// Writes `path` atomically (io/atomic_file.hpp): a reader sees the previous file or the whole new one.
void write_checkpoint_file(const std::string& path, const CheckpointFile& checkpoint);
// Reads and verifies `path`; throws mipnerf::Error naming the file and what is wrong.
CheckpointFile read_checkpoint_file(const std::string& path);

}  // namespace mipnerf::io
