// The checkpoint file format: write, and verify-then-parse (format 2), plus the reader of format 1.
#include "io/checkpoint_file.hpp"

#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <limits>

#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/file.hpp"

namespace mipnerf::io {
namespace {

constexpr std::string_view kMagicPrefix = "MNCKPT";  // then two digits: the format
constexpr std::string_view kMagic2 = "MNCKPT02";
constexpr std::string_view kMagic1 = "MNCKPT01";
constexpr size_t kMagicBytes = 8;
constexpr size_t kPreamble2 = kMagicBytes + 8 + 8;  // magic, file bytes, header bytes
constexpr size_t kPreamble1 = kMagicBytes + 8;      // magic, header bytes
constexpr size_t kTrailerBytes = 4;                 // the CRC-32

// CRC-32 (zlib's) of any number of bytes: zlib takes at most 4 GiB - 1 per call.
uint32_t crc32_of(const char* data, size_t size) {
  uLong crc = crc32(0L, Z_NULL, 0);
  while (size > 0) {
    const size_t piece = std::min<size_t>(size, std::numeric_limits<uInt>::max());
    crc = crc32(crc, reinterpret_cast<const Bytef*>(data), static_cast<uInt>(piece));
    data += piece;
    size -= piece;
  }
  return static_cast<uint32_t>(crc);
}

uint32_t crc32_of(const std::vector<float>& values) {
  // Checkpoints are written and read on little-endian hosts (x86-64, AArch64); the CRC covers the bytes.
  return crc32_of(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(float));
}

void append_le(std::string& out, uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

uint64_t read_le(std::string_view bytes, size_t at, int count) {
  uint64_t v = 0;
  for (int i = 0; i < count; ++i) v |= static_cast<uint64_t>(static_cast<unsigned char>(bytes[at + i])) << (8 * i);
  return v;
}

nlohmann::json parse_header(std::string_view text, const std::string& where) {
  nlohmann::json header;
  try {
    header = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw Error(where + ": corrupt checkpoint: its header is not JSON (" + e.what() + ")");
  }
  if (!header.is_object() || !header.contains("tensors") || !header["tensors"].is_array()) {
    throw Error(where + ": corrupt checkpoint: its header lists no tensors");
  }
  return header;
}

// The tensors the header lists, read from `bytes` at `at` (advanced past them). `check_crc`: format 1's CRC-32
// per tensor. Counts are checked against the bytes left before anything is allocated.
void read_tensors(std::string_view bytes, size_t& at, size_t end, bool check_crc, const std::string& where,
                  CheckpointFile& checkpoint) {
  for (const auto& entry : checkpoint.header["tensors"]) {
    const auto name = entry.is_object() ? entry.find("name") : entry.end();
    const auto count = entry.is_object() ? entry.find("count") : entry.end();
    if (name == entry.end() || !name->is_string() || count == entry.end() || !count->is_number_unsigned()) {
      throw Error(where + ": corrupt checkpoint: a tensor entry of its header lacks a name or an element count");
    }
    const uint64_t n = count->get<uint64_t>();
    if (n > (end - at) / sizeof(float)) {
      throw Error(where + ": truncated or corrupt checkpoint: tensor '" + name->get<std::string>() + "' runs past the end");
    }
    std::vector<float> values(n);
    if (n > 0) std::memcpy(values.data(), bytes.data() + at, n * sizeof(float));  // an empty vector's data() may be null
    at += n * sizeof(float);
    if (check_crc) {
      const auto crc = entry.find("crc32");
      if (crc == entry.end() || !crc->is_number_unsigned() || crc->get<uint64_t>() != crc32_of(values)) {
        throw Error(where + ": corrupt checkpoint: tensor '" + name->get<std::string>() + "' fails its CRC-32 check");
      }
    }
    checkpoint.add(name->get<std::string>(), std::move(values));
  }
  if (at != end) {
    throw Error(where + ": corrupt checkpoint: " + std::to_string(end - at) + " bytes after its last tensor");
  }
  checkpoint.header.erase("tensors");
}

CheckpointFile parse_format2(std::string_view bytes, const std::string& where) {
  if (bytes.size() < kPreamble2 + kTrailerBytes) throw Error(where + ": truncated checkpoint (" + std::to_string(bytes.size()) + " bytes)");
  const uint64_t file_bytes = read_le(bytes, kMagicBytes, 8);
  if (file_bytes != bytes.size()) {
    throw Error(where + ": truncated or corrupt checkpoint: it holds " + std::to_string(bytes.size()) +
                " bytes, its preamble says " + std::to_string(file_bytes));
  }
  const size_t covered = bytes.size() - kTrailerBytes;
  if (crc32_of(bytes.data(), covered) != static_cast<uint32_t>(read_le(bytes, covered, 4))) {
    throw Error(where + ": corrupt checkpoint: its CRC-32 does not match its contents (changed after it was written)");
  }
  const uint64_t header_bytes = read_le(bytes, kMagicBytes + 8, 8);
  if (header_bytes > covered - kPreamble2) throw Error(where + ": corrupt checkpoint: its header runs past the end");
  CheckpointFile checkpoint;
  checkpoint.header = parse_header(bytes.substr(kPreamble2, header_bytes), where);
  size_t at = kPreamble2 + header_bytes;
  read_tensors(bytes, at, covered, false, where, checkpoint);
  return checkpoint;
}

CheckpointFile parse_format1(std::string_view bytes, const std::string& where) {
  if (bytes.size() < kPreamble1) throw Error(where + ": truncated checkpoint (" + std::to_string(bytes.size()) + " bytes)");
  const uint64_t header_bytes = read_le(bytes, kMagicBytes, 8);
  if (header_bytes > bytes.size() - kPreamble1) throw Error(where + ": truncated or corrupt checkpoint (header)");
  CheckpointFile checkpoint;
  checkpoint.header = parse_header(bytes.substr(kPreamble1, header_bytes), where);
  size_t at = kPreamble1 + header_bytes;
  read_tensors(bytes, at, bytes.size(), true, where, checkpoint);
  return checkpoint;
}

}  // namespace

const std::vector<float>& CheckpointFile::tensor(const std::string& name, const std::string& where) const {
  for (const auto& [n, values] : tensors) {
    if (n == name) return values;
  }
  throw Error(where + ": checkpoint has no tensor '" + name + "' (was it written by another model configuration?)");
}

std::string checkpoint_bytes(const CheckpointFile& checkpoint) {
  nlohmann::json header = checkpoint.header;
  header["tensors"] = nlohmann::json::array();
  size_t tensor_bytes = 0;
  for (const auto& [name, values] : checkpoint.tensors) {
    header["tensors"].push_back({{"name", name}, {"count", values.size()}});
    tensor_bytes += values.size() * sizeof(float);
  }
  const std::string header_text = header.dump();
  const size_t file_bytes = kPreamble2 + header_text.size() + tensor_bytes + kTrailerBytes;
  std::string bytes(kMagic2);
  bytes.reserve(file_bytes);
  append_le(bytes, file_bytes, 8);
  append_le(bytes, header_text.size(), 8);
  bytes += header_text;
  for (const auto& [name, values] : checkpoint.tensors) {
    bytes.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(float));
  }
  append_le(bytes, crc32_of(bytes.data(), bytes.size()), 4);
  return bytes;
}

CheckpointFile parse_checkpoint(std::string_view bytes, const std::string& where) {
  const std::string_view magic = bytes.substr(0, kMagicBytes);
  if (magic == kMagic2) return parse_format2(bytes, where);
  if (magic == kMagic1) return parse_format1(bytes, where);
  if (magic.substr(0, kMagicPrefix.size()) == kMagicPrefix) {
    const std::string_view version = magic.substr(kMagicPrefix.size());
    const bool digits = std::all_of(version.begin(), version.end(), [](char c) { return c >= '0' && c <= '9'; });
    throw Error(where + ": corrupt checkpoint, or one from a newer mipnerf-cl: unknown format" +
                (digits ? " '" + std::string(version) + "'" : std::string()) + " (this version reads 01 and 02)");
  }
  throw Error(where + ": not a mipnerf-cl checkpoint, or a corrupt one (it does not start with " + std::string(kMagic2) +
              ")");
}

void write_checkpoint_file(const std::string& path, const CheckpointFile& checkpoint) {
  write_bytes_atomically(path, checkpoint_bytes(checkpoint));
}

CheckpointFile read_checkpoint_file(const std::string& path) {
  std::string bytes;
  try {
    bytes = read_file_text(path);
  } catch (const Error& e) {
    throw Error(std::string(e.what()) + " (expected a checkpoint)");
  }
  return parse_checkpoint(bytes, path);
}

}  // namespace mipnerf::io
