// Shared by the render and eval tests: a small procedural scene and a tiny model trained on it for a few steps,
// made once per test process in temporary folders; and running the real mipnerf-cl executable.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "eval/image_renderer.hpp"
#include "support/temp_scene.hpp"
#include "support/test_context.hpp"
#include "train/checkpoint.hpp"
#include "train/model.hpp"
#include "train/trainer.hpp"

namespace mipnerf::test {

inline std::filesystem::path render_temp(const std::string& name) { return temp_path("render-" + name); }

// A 16×16 procedural scene: 8 train views, 2 val, 2 test, and OUT/multiscale with 2 scales (16 and 8 pixels: the
// second smaller than SSIM's 11×11 window). Small, so every test renders in seconds on two CPU cores.
inline const std::string& render_scene() {
  static const std::string path = write_temp_scene("render-scene", {16, 8, 2, 2, 2});
  return path;
}

// The tiny preset trained for 10 steps of 128 rays on render_scene(); returns its checkpoint. Little is learnt in
// 10 steps: the tests check rendering, not learning (tests/train does that); the IPE features of a barely trained
// network still make renders vary across the image.
inline const std::string& trained_checkpoint() {
  static const std::string path = [] {
    const auto out = render_temp("run");
    std::filesystem::remove_all(out);
    const auto config = train::resolve_config("tiny", "mipnerf", {{"steps", "10"}, {"batch_size", "128"}});
    train::Trainer trainer(test_context(), config, render_scene(), out.string(), false);
    return trainer.run().checkpoint;
  }();
  return path;
}

// trained_checkpoint() loaded once per test process: its networks on the test device, its graph spec and config.
inline train::TrainedModel& trained_model() {
  static train::TrainedModel trained = train::load_trained_model(test_context(), trained_checkpoint());
  return trained;
}

// A renderer of trained_model() over `cameras`.
inline eval::ImageRenderer trained_renderer(const std::vector<Camera>& cameras,
                                            const eval::RenderSettings& settings) {
  return eval::ImageRenderer(test_context(), trained_model().spec, trained_model().network_pointers(), cameras,
                             settings);
}

struct CliResult {
  int exit_code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

// Runs `mipnerf-cl ARGS` (the build's executable) on the tests' device; the kernel cache comes from the environment.
inline CliResult run_cli(const std::string& args) {
  const auto dir = render_temp("cli-output");
  std::filesystem::create_directories(dir);
  const std::string out = (dir / "stdout").string(), err = (dir / "stderr").string();
  // The device the in-process tests use (test_context: MIPNERF_TEST_DEVICE, else the first CPU).
  const std::string device_flag = " --device " + std::to_string(test_context().device_info().index);
  const std::string command =
      std::string("\"") + MIPNERF_CLI_PATH + "\"" + device_flag + " " + args + " >" + out + " 2>" + err;
  CliResult result;
  const int status = std::system(command.c_str());
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  auto slurp = [](const std::string& file) {
    std::ifstream in(file);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  };
  result.out = slurp(out);
  result.err = slurp(err);
  return result;
}

}  // namespace mipnerf::test
