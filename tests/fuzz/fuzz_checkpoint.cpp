// Fuzz target: a checkpoint file (render/eval --checkpoint, train --resume): io::parse_checkpoint (formats 1 and 2),
// then, for what parses, the trainer's header (train::read_checkpoint_header: record, configuration, Adam steps).
// Format 2 checks one CRC-32 over the whole file before parsing anything, so random mutations would mostly stop
// there; each format-2 input is therefore also tried with its length field and CRC-32 made to match, which lets the
// fuzzer reach the header and tensor parsing behind the checksum.
#include <zlib.h>

#include <string>
#include <string_view>

#include "fuzz_support.hpp"
#include "io/checkpoint_file.hpp"
#include "train/checkpoint.hpp"

namespace {

void read_checkpoint(std::string_view bytes) {
  using namespace mipnerf;
  fuzz::expect_only_errors("fuzz.mnck", [&] {
    const io::CheckpointFile file = io::parse_checkpoint(bytes, "fuzz.mnck");
    const train::CheckpointHeader header = train::read_checkpoint_header(file, "fuzz.mnck");
    fuzz::check(header.record.step >= 0, "a checkpoint with a negative step was accepted");
  });
}

// `bytes` with format 2's file length (bytes 8-15) and trailing CRC-32 set to match it.
std::string with_matching_checksum(std::string bytes) {
  const uint64_t size = bytes.size();
  for (int i = 0; i < 8; ++i) bytes[8 + i] = static_cast<char>((size >> (8 * i)) & 0xff);
  const size_t covered = bytes.size() - 4;
  const uLong crc = crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(covered));
  for (int i = 0; i < 4; ++i) bytes[covered + i] = static_cast<char>((crc >> (8 * i)) & 0xff);
  return bytes;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  read_checkpoint(bytes);
  if (bytes.size() >= 28 && bytes.substr(0, 8) == "MNCKPT02") read_checkpoint(with_matching_checksum(std::string(bytes)));
  return 0;
}
