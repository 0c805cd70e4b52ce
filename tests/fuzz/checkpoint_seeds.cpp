// Writes the checkpoint fuzz target's seeds into a folder (tests/fuzz/corpus/checkpoint was made with it):
//   tiny_training.mnck  a training checkpoint of a minute model, saved by the library (format 2) on the default device
//   tiny_training_format1.mnck  the same header and tensors in format 1 (magic, header length, header with a CRC-32
//                               per tensor, tensors), as checkpoints were written before the whole-file checksum
//   bare.mnck           format 2 with an empty header and one tensor of two values
//   fuzz_checkpoint_seeds DIR
#include <zlib.h>

#include <cstdio>
#include <fstream>

#include "cl/device.hpp"
#include "core/error.hpp"
#include "io/checkpoint_file.hpp"
#include "train/checkpoint.hpp"
#include "train/model.hpp"

namespace {
using namespace mipnerf;

void write(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

void append_le(std::string& out, uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

std::string format1_bytes(const io::CheckpointFile& checkpoint) {
  nlohmann::json header = checkpoint.header;
  header["tensors"] = nlohmann::json::array();
  std::string tensors;
  for (const auto& [name, values] : checkpoint.tensors) {
    const auto* raw = reinterpret_cast<const Bytef*>(values.data());
    const uInt length = static_cast<uInt>(values.size() * sizeof(float));
    header["tensors"].push_back({{"name", name}, {"count", values.size()}, {"crc32", crc32(crc32(0L, Z_NULL, 0), raw, length)}});
    tensors.append(reinterpret_cast<const char*>(raw), length);
  }
  const std::string text = header.dump();
  std::string bytes = "MNCKPT01";
  append_le(bytes, text.size(), 8);
  return bytes + text + tensors;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_checkpoint_seeds DIR\n");
    return 2;
  }
  try {
    const std::string dir = argv[1];
    ocl::Context ctx(ocl::choose_device(ocl::list_devices(), ""));
    const train::TrainConfig config = train::resolve_config(
        "tiny", "mipnerf",
        {{"mlp_depth", "1"}, {"mlp_width", "2"}, {"mlp_skip", "4"}, {"view_branch_width", "1"}, {"pos_max_deg", "1"},
         {"view_max_deg", "1"}, {"num_samples", "2"}});
    const auto spec = train::make_graph_spec(config, false);
    auto networks = train::make_networks(ctx, spec, gemm::GemmBackend::automatic);
    std::vector<std::unique_ptr<mlp::Adam>> optimisers;
    for (const auto& network : networks) optimisers.push_back(std::make_unique<mlp::Adam>(ctx, network->parameter_count()));
    train::CheckpointRecord record;
    record.step = 3;
    record.train_seconds = 1.5;
    record.device = ctx.device_info().name;
    record.data_path = "/data/scene";
    train::save_training_checkpoint(dir + "/tiny_training.mnck", config, record, networks, optimisers);
    write(dir + "/tiny_training_format1.mnck", format1_bytes(io::read_checkpoint_file(dir + "/tiny_training.mnck")));
    io::CheckpointFile bare;
    bare.add("values", {1.0f, -2.5f});
    io::write_checkpoint_file(dir + "/bare.mnck", bare);
  } catch (const Error& e) {
    std::fprintf(stderr, "fuzz_checkpoint_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
