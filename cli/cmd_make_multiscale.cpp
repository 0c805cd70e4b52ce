// `mipnerf-cl make-multiscale IN OUT`: the paper's multiscale Blender dataset from a Blender folder.
#include <iostream>
#include <memory>

#include "common.hpp"
#include "data/multiscale.hpp"

namespace mipnerf::cli {

void register_make_multiscale(CLI::App& app) {
  struct Args {
    std::string in, out;
    int scales = 4;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "make-multiscale",
      "Write the multiscale version of a Blender dataset as the paper builds it: every image box-downsampled x2, "
      "x4, x8 (RGBA averaged), metadata.json with per-image focal, size and lossmult 1, 4, 16, 64");
  cmd->add_option("IN", args->in, "Blender dataset folder (or transforms.json)")->required();
  cmd->add_option("OUT", args->out, "Output folder")->required();
  cmd->add_option("--scales", args->scales, "Number of scales including full resolution")
      ->check(CLI::Range(1, 8))
      ->capture_default_str();
  cmd->callback([args] {
    data::write_multiscale(args->in, args->out, args->scales, print_log);
    std::cout << "wrote " << args->out << "/metadata.json (" << args->scales << " scales)\n";
  });
}

}  // namespace mipnerf::cli
