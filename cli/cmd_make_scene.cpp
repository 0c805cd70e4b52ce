// `mipnerf-cl make-scene OUT`: writes the built-in procedural scene (Blender format, plus OUT/multiscale).
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>

#include "common.hpp"
#include "data/procedural.hpp"

namespace mipnerf::cli {

void register_make_scene(CLI::App& app) {
  auto out = std::make_shared<std::string>();
  auto options = std::make_shared<data::SceneOptions>();
  auto* cmd = app.add_subcommand(
      "make-scene",
      "Render the built-in procedural scene (checkered sphere, striped boxes; anti-aliased by jittered "
      "supersampling) into OUT in the Blender format, with OUT/multiscale holding its multiscale version");
  cmd->add_option("OUT", *out, "Output folder (created; existing files of the same names are replaced)")->required();
  cmd->add_option("--size", options->size_px, "Image width and height in pixels")->capture_default_str();
  cmd->add_option("--views", options->train_views, "Training views (random, upper hemisphere)")->capture_default_str();
  cmd->add_option("--val-views", options->val_views, "Validation views (orbit at 25 degrees)")->capture_default_str();
  cmd->add_option("--test-views", options->test_views, "Test views (orbit at 40 degrees)")->capture_default_str();
  cmd->add_option("--scales", options->scales, "Scales of OUT/multiscale (1 = none; the paper: 4)")
      ->capture_default_str();
  cmd->add_option("--seed", options->seed, "Seed of camera placement and jitter")->capture_default_str();
  cmd->add_option("--samples", options->samples_per_axis, "Jittered rays per pixel per axis (8: 64 rays per pixel)")
      ->capture_default_str();
  cmd->add_option("--threads", options->threads, "Render threads (0: all hardware threads)")->capture_default_str();
  cmd->callback([out, options] {
    data::write_procedural_scene(*out, *options, print_log);
    std::cout << "wrote " << *out << ": " << options->train_views << " train, " << options->val_views << " val, "
              << options->test_views << " test views at " << options->size_px << "x" << options->size_px;
    if (options->scales > 1) std::cout << "; multiscale (" << options->scales << " scales) in " << *out << "/multiscale";
    std::cout << "\n";
  });
}

}  // namespace mipnerf::cli
