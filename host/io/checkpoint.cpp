// Checkpoint files: header + tensors, atomic writes, checked reads.
#include "io/checkpoint.hpp"

#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "core/error.hpp"
#include "io/atomic_file.hpp"

namespace mipnerf::io {
namespace {

constexpr char kMagic[8] = {'M', 'N', 'C', 'K', 'P', 'T', '0', '1'};

uint32_t crc_of(const std::vector<float>& values) {
  // Checkpoints are written and read on little-endian hosts (x86-64, AArch64); the CRC covers the bytes.
  return static_cast<uint32_t>(crc32(0L, reinterpret_cast<const Bytef*>(values.data()),
                                     static_cast<uInt>(values.size() * sizeof(float))));
}

void append_u64(std::string& out, uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

uint64_t read_u64(const std::string& bytes, size_t at) {
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<uint64_t>(static_cast<unsigned char>(bytes[at + i])) << (8 * i);
  return v;
}

}  // namespace

const std::vector<float>& Checkpoint::tensor(const std::string& name, const std::string& where) const {
  for (const auto& [n, values] : tensors) {
    if (n == name) return values;
  }
  throw Error(where + ": checkpoint has no tensor '" + name + "' (was it written by another model configuration?)");
}

void write_checkpoint(const std::string& path, const Checkpoint& checkpoint) {
  nlohmann::json header = checkpoint.header;
  header["tensors"] = nlohmann::json::array();
  for (const auto& [name, values] : checkpoint.tensors) {
    header["tensors"].push_back({{"name", name}, {"count", values.size()}, {"crc32", crc_of(values)}});
  }
  const std::string header_text = header.dump();
  std::string bytes(kMagic, sizeof(kMagic));
  append_u64(bytes, header_text.size());
  bytes += header_text;
  for (const auto& [name, values] : checkpoint.tensors) {
    bytes.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(float));
  }
  write_bytes_atomically(path, bytes);
}

Checkpoint read_checkpoint(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open the checkpoint (does the file exist?)");
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.size() < 16 || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    throw Error(path + ": not a mipnerf-cl checkpoint (bad magic)");
  }
  const uint64_t header_length = read_u64(bytes, 8);
  if (header_length > bytes.size() - 16) throw Error(path + ": truncated checkpoint (header)");
  Checkpoint checkpoint;
  try {
    checkpoint.header = nlohmann::json::parse(bytes.substr(16, header_length));
  } catch (const nlohmann::json::exception& e) {
    throw Error(path + ": corrupted checkpoint header: " + e.what());
  }
  size_t at = 16 + header_length;
  for (const auto& entry : checkpoint.header.at("tensors")) {
    const std::string name = entry.at("name").get<std::string>();
    const uint64_t count = entry.at("count").get<uint64_t>();
    if (count > (bytes.size() - at) / sizeof(float)) throw Error(path + ": truncated checkpoint (tensor " + name + ")");
    std::vector<float> values(count);
    std::memcpy(values.data(), bytes.data() + at, count * sizeof(float));
    at += count * sizeof(float);
    if (crc_of(values) != entry.at("crc32").get<uint32_t>()) {
      throw Error(path + ": corrupted checkpoint: tensor '" + name + "' fails its CRC-32 check");
    }
    checkpoint.add(name, std::move(values));
  }
  if (at != bytes.size()) throw Error(path + ": checkpoint has " + std::to_string(bytes.size() - at) + " extra bytes");
  checkpoint.header.erase("tensors");
  return checkpoint;
}

std::string checkpoint_path(const std::string& folder, int64_t step) {
  char name[64];
  std::snprintf(name, sizeof(name), "ckpt_%09lld.mnck", static_cast<long long>(step));
  return (std::filesystem::path(folder) / name).string();
}

std::vector<std::pair<int64_t, std::string>> list_checkpoints(const std::string& folder) {
  std::vector<std::pair<int64_t, std::string>> found;
  std::error_code ec;
  if (!std::filesystem::is_directory(folder, ec)) return found;
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
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
    std::filesystem::remove(all[i].second, ec);
  }
}

}  // namespace mipnerf::io
