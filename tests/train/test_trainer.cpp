// End-to-end training on the device: learning, resume equality, non-finite steps, an all-background scene, every
// variant.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "eval/evaluate.hpp"
#include "eval/image_renderer.hpp"
#include "eval/metrics.hpp"
#include "io/json.hpp"
#include "io/png.hpp"
#include "data/pose.hpp"
#include "support/test_context.hpp"
#include "train/checkpoint.hpp"
#include "data/synthetic/forward_facing.hpp"
#include "train/model.hpp"
#include "train/scene_effects.hpp"
#include "train/trainer.hpp"
#include "support/train_fixtures.hpp"

using namespace mipnerf;
namespace fs = std::filesystem;

namespace {

train::TrainConfig tiny(std::map<std::string, std::string> extra = {}, const std::string& variant = "mipnerf") {
  extra.emplace("log_every", "1");
  return train::resolve_config("tiny", variant, extra);
}

// Mean PSNR over the val split of the best constant image: every pixel the mean colour of the training
// pixels. A model that learnt nothing about the scene's geometry can do no better than this.
double constant_colour_val_psnr(const std::string& scene, const data::LoadOptions& options = {}) {
  const auto dataset = data::load_dataset(scene, options);
  const auto& train = dataset.split("train");
  double mean[3] = {0, 0, 0};
  for (uint64_t p = 0; p < train.num_pixels(); ++p) {
    for (int c = 0; c < 3; ++c) mean[c] += train.rgb[3 * p + c] / static_cast<double>(train.num_pixels());
  }
  const auto& val = dataset.split("val");
  double sum = 0.0;
  for (size_t i = 0; i < val.num_images(); ++i) {
    const auto& cam = val.cameras[i];
    std::vector<float> constant(3 * cam.width_px * cam.height_px);
    for (size_t k = 0; k < constant.size(); ++k) constant[k] = static_cast<float>(mean[k % 3]);
    sum += eval::psnr({constant.data(), cam.height_px, cam.width_px, 3}, {val.image_rgb(i), cam.height_px, cam.width_px, 3});
  }
  return sum / static_cast<double>(val.num_images());
}

eval::SplitScores evaluate_val(ocl::Context& ctx, train::Trainer& trainer, const std::string& scene,
                               const data::LoadOptions& options = {}) {
  const auto dataset = data::load_dataset(scene, options);
  const auto& val = dataset.split("val");
  std::vector<mlp::Network*> networks;
  for (auto& n : trainer.networks()) networks.push_back(n.get());
  eval::ImageRenderer renderer(ctx, trainer.spec(), networks, val.cameras, 1024);
  return eval::evaluate_split(renderer, val, {});
}

bool bitwise_equal(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

}  // namespace

TEST_CASE("train: a tiny procedural scene learns beyond its mean colour in a few hundred steps") {
  auto& ctx = test::test_context();
  const std::string out = test::fresh_run_dir("learn");
  train::Trainer trainer(ctx, tiny({{"steps", "250"}, {"batch_size", "256"}}), test::small_scene(), out, false);
  const auto result = trainer.run();
  CHECK(result.last_step == 250);
  CHECK(result.skipped_steps == 0);
  const double baseline = constant_colour_val_psnr(test::small_scene());
  const auto scores = evaluate_val(ctx, trainer, test::small_scene());
  MESSAGE("val PSNR " << scores.mean_psnr << " dB after 250 steps (" << result.train_seconds
                      << " s); best constant colour " << baseline << " dB");
  // 3 dB over the constant image halves the error energy: only possible by learning where the objects are.
  CHECK(scores.mean_psnr > baseline + 3.0);
  CHECK(std::isfinite(scores.mean_ssim));
  // The log has a row per step (log_every 1) with a rising trend: the last 25 steps beat the first 25.
  std::ifstream csv(fs::path(out) / "train_log.csv");
  std::string line;
  std::getline(csv, line);
  CHECK(line == "step,wall_seconds,loss,psnr,learning_rate,rays_per_second,skipped");
  std::vector<double> psnr;
  while (std::getline(csv, line)) {
    std::stringstream row(line);
    std::string field;
    for (int k = 0; k < 4; ++k) std::getline(row, field, ',');
    psnr.push_back(std::stod(field));
  }
  REQUIRE(psnr.size() == 250);
  double first = 0, last = 0;
  for (int k = 0; k < 25; ++k) first += psnr[k] / 25, last += psnr[psnr.size() - 1 - k] / 25;
  CHECK(last > first + 2.0);
  fs::remove_all(out);
}

namespace {

// Runs `config` (8 steps) straight, and again stopped at step 4 and resumed; the two end bit for bit alike.
void check_resume_bit_exact(const train::TrainConfig& config, const std::string& name) {
  auto& ctx = test::test_context();
  const std::string straight_dir = test::fresh_run_dir(name + "-straight"),
                    resumed_dir = test::fresh_run_dir(name + "-resumed");
  std::vector<float> straight_params;
  {
    train::Trainer trainer(ctx, config, test::small_scene(), straight_dir, false);
    trainer.run();
    straight_params = trainer.networks()[0]->download_params();
  }
  {
    train::Trainer first(ctx, config, test::small_scene(), resumed_dir, false);
    train::TrainHooks hooks;
    hooks.should_stop = [&first] { return first.step() >= 4; };  // what Ctrl-C does, at step 4
    const auto result = first.run(hooks);
    CHECK(result.interrupted);
    CHECK(result.last_step == 4);
  }
  CHECK_THROWS_WITH_AS(train::Trainer(ctx, config, test::small_scene(), resumed_dir, false),
                       doctest::Contains("--resume"), Error);
  train::Trainer second(ctx, config, test::small_scene(), resumed_dir, true);
  CHECK(second.step() == 4);
  const auto result = second.run();
  CHECK(result.last_step == 8);
  CHECK(bitwise_equal(second.networks()[0]->download_params(), straight_params));
  // Both runs' final checkpoints hold the same Adam moments too.
  const auto a =
      io::read_checkpoint_file(train::checkpoint_path((fs::path(straight_dir) / "checkpoints").string(), 8));
  const auto b =
      io::read_checkpoint_file(train::checkpoint_path((fs::path(resumed_dir) / "checkpoints").string(), 8));
  // Every network's and grid's parameters and Adam moments (Zip-NeRF's proposal rounds have several of each).
  std::vector<std::string> tensors;
  for (size_t i = 0; i < second.networks().size(); ++i) tensors.push_back("network" + std::to_string(i));
  for (size_t i = 0; i < second.spec().grids.size(); ++i) tensors.push_back("grid" + std::to_string(i));
  for (const auto& prefix : tensors) {
    for (const char* part : {".params", ".adam_m", ".adam_v"}) {
      INFO(prefix << part);
      CHECK(bitwise_equal(a.tensor(prefix + part, "a"), b.tensor(prefix + part, "b")));
    }
  }
  CHECK(a.header["adam_steps"] == b.header["adam_steps"]);
  CHECK(a.header.value("grid_adam_steps", nlohmann::json()) == b.header.value("grid_adam_steps", nlohmann::json()));
  // A resume with different learning settings is refused, naming them.
  auto other = config;
  other.batch_size = 64;
  CHECK_THROWS_WITH_AS(train::Trainer(ctx, other, test::small_scene(), resumed_dir, true),
                       doctest::Contains("batch_size: 96 -> 64"), Error);
  fs::remove_all(straight_dir);
  fs::remove_all(resumed_dir);
}

}  // namespace

TEST_CASE("train: N steps straight equal N/2 steps, resume, N/2 steps, bit for bit") {
  check_resume_bit_exact(tiny({{"steps", "8"}, {"batch_size", "96"}, {"chunk_rays", "32"}}), "plain");
}

// The density noise is drawn from the step's key (seed, step, ray in the batch, level, sample), not from a stream that
// advances, so a resumed run draws what the straight run drew; raw view directions ride along. A resume that changes
// the noise is refused like any other learning setting.
// Zip-NeRF's proposal sampling: the rounds' networks and grids, their anneal (a function of the step) and their jitter
// (keyed by seed, step, round and ray) resume exactly too; and the trained model renders (the rounds for weights only)
// and its losses are logged: the rounds' interlevel losses are finite and part of the total.
TEST_CASE("train: Zip-NeRF with proposal sampling resumes bit for bit and renders") {
  const auto config = tiny({{"steps", "8"}, {"batch_size", "96"}, {"chunk_rays", "32"}, {"sampler", "proposal"},
                            {"proposal_samples", "8"}, {"num_samples", "8"}, {"proposal_grid_max", "64"},
                            {"grid_max", "64"}, {"grid_hash_log2", "12"}},
                           "zipnerf");
  check_resume_bit_exact(config, "proposal");
  auto& ctx = test::test_context();
  const std::string out = test::fresh_run_dir("proposal-render");
  train::Trainer trainer(ctx, config, test::small_scene(), out, false);
  REQUIRE(trainer.spec().has_proposal_levels());
  CHECK(trainer.networks().size() == 3);
  const auto result = trainer.run();
  CHECK(result.skipped_steps == 0);
  CHECK(std::isfinite(result.final_psnr));
  auto model = train::load_trained_model(ctx, train::find_checkpoint(out));
  CHECK(model.grids.size() == 3);
  CHECK(model.networks.size() == 3);
  const auto dataset = data::load_dataset(test::small_scene(), {});
  eval::ImageRenderer renderer(ctx, model.spec, model.network_pointers(), model.grid_pointers(),
                               dataset.split("val").cameras, eval::RenderSettings{512, 1, 0});
  const auto image = renderer.render(0);
  CHECK(image.width > 0);
  for (float v : image.rgb) REQUIRE(std::isfinite(v));
  for (float d : image.depth) REQUIRE(std::isfinite(d));
  fs::remove_all(out);
}

TEST_CASE("train: with density noise and raw view directions, resume is still bit for bit") {
  const auto config = tiny(
      {{"steps", "8"}, {"batch_size", "96"}, {"chunk_rays", "32"}, {"density_noise", "1"}, {"unit_viewdirs", "false"}});
  check_resume_bit_exact(config, "noise");
  auto& ctx = test::test_context();
  const std::string out = test::fresh_run_dir("noise-changed");
  {
    train::Trainer first(ctx, config, test::small_scene(), out, false);
    train::TrainHooks hooks;
    hooks.should_stop = [&first] { return first.step() >= 2; };
    first.run(hooks);
  }
  auto quieter = config;
  quieter.density_noise = 0.5;
  CHECK_THROWS_WITH_AS(train::Trainer(ctx, quieter, test::small_scene(), out, true),
                       doctest::Contains("density_noise: 1 -> 0.5"), Error);
  fs::remove_all(out);
}

TEST_CASE("train: --resume skips checkpoints that fail to verify, removes dead writers' temporaries, trims the log") {
  auto& ctx = test::test_context();
  const auto config = tiny({{"steps", "6"}, {"batch_size", "64"}, {"checkpoint_every", "2"}, {"keep_checkpoints", "3"}});
  const std::string out = test::fresh_run_dir("resume-verify");
  const std::string folder = (fs::path(out) / "checkpoints").string();
  std::vector<float> params_at_4;
  {
    train::Trainer trainer(ctx, config, test::small_scene(), out, false);
    trainer.run();
    params_at_4 = io::read_checkpoint_file(train::checkpoint_path(folder, 4)).tensor("network0.params", "4");
  }
  // The newest checkpoint loses one byte of its header's JSON (the kind of damage format 1 missed); a process that
  // no longer exists left a temporary; the log has a row cut short by the kill.
  const std::string newest = train::checkpoint_path(folder, 6);
  std::string bytes;
  {
    std::ifstream in(newest, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  bytes[30] = bytes[30] == 'x' ? 'y' : 'x';
  std::ofstream(newest, std::ios::binary | std::ios::trunc) << bytes;
  const fs::path stale = fs::path(folder) / ".ckpt_000000008.mnck.999999999.0.tmp";  // pid 999999999: none
  std::ofstream(stale) << "half a checkpoint";
  const fs::path live = fs::path(folder) / (".ckpt_000000008.mnck." + std::to_string(::getppid()) + ".0.tmp");
  std::ofstream(live) << "a live writer's";
  const fs::path csv = fs::path(out) / "train_log.csv";
  std::ofstream(csv, std::ios::app) << "7,0.1,0.5";

  train::Trainer resumed(ctx, config, test::small_scene(), out, true);
  CHECK(resumed.step() == 4);
  CHECK(bitwise_equal(resumed.networks()[0]->download_params(), params_at_4));
  CHECK(fs::exists(newest + ".corrupt"));
  CHECK(!fs::exists(newest));
  CHECK(!fs::exists(stale));
  CHECK(fs::exists(live));  // its process runs: never touched
  std::ifstream log(csv);
  std::string line, last;
  int rows = 0;
  while (std::getline(log, line)) {
    ++rows;
    last = line;
  }
  CHECK(rows == 1 + 4);  // the header, steps 1…4 (5 and 6 are trained again, the cut row is gone)
  CHECK(last.rfind("4,", 0) == 0);

  // When nothing verifies, --resume stops with one line and starts nothing.
  for (const auto& [step, path] : train::list_checkpoints(folder)) {
    std::ofstream(path, std::ios::binary | std::ios::in | std::ios::out) << "MNCKPT99";
  }
  CHECK_THROWS_WITH_AS(train::Trainer(ctx, config, test::small_scene(), out, true),
                       doctest::Contains("none of the 2 checkpoints in"), Error);
  fs::remove_all(out);
}

TEST_CASE("train: config.json and checkpoints record the variant, and a checkpoint from before that loads and resumes") {
  auto& ctx = test::test_context();
  const std::string out = test::fresh_run_dir("variant-record");
  const auto two_steps = tiny({{"steps", "2"}, {"batch_size", "64"}}, "mipnerf-two-mlps");
  {
    train::Trainer trainer(ctx, two_steps, test::small_scene(), out, false);
    trainer.run();
  }
  std::ifstream config_file(fs::path(out) / "config.json");
  const auto written = nlohmann::json::parse(config_file);
  CHECK(written.at("variant_bundle") == "mipnerf-two-mlps");
  CHECK(written.at("variant") == "mipnerf");
  const std::string path = train::find_checkpoint(out);
  io::CheckpointFile checkpoint = io::read_checkpoint_file(path);
  CHECK(checkpoint.header.at("config").at("variant_bundle") == "mipnerf-two-mlps");
  const auto model = train::load_trained_model(ctx, path);
  REQUIRE(model.config.variant_bundle.has_value());
  CHECK(*model.config.variant_bundle == train::Variant::mipnerf_two_mlps);

  // The same checkpoint as written before the variant was recorded: its configuration has no such key.
  checkpoint.header["config"].erase("variant_bundle");
  io::write_checkpoint_file(path, checkpoint);
  const auto old = train::load_trained_model(ctx, path);
  CHECK(!old.config.variant_bundle.has_value());
  CHECK(old.networks.size() == 2);
  CHECK(old.step == 2);
  auto more_steps = two_steps;
  more_steps.steps = 3;
  train::Trainer resumed(ctx, more_steps, test::small_scene(), out, true);
  CHECK(resumed.step() == 2);
  CHECK(resumed.run().last_step == 3);
  fs::remove_all(out);
}

TEST_CASE("train: 500 steps on an all-background scene stay finite - losses, parameters, moments and a render") {
  // Every pixel of every image is the background: fully transparent PNGs, composited onto the white background.
  // The best model is empty space (acc → 0, density pushed towards 0 through the softplus), the regime where
  // the density and colour activations saturate and the loss can reach exactly 0 (PSNR +∞, a legitimate value);
  // nothing may become NaN or ±∞ on the way.
  auto& ctx = test::test_context();
  const auto scene = test::fresh_temp_dir("background-scene");
  const uint32_t size = 24;
  const std::vector<uint8_t> transparent(4 * size * size, 0);
  const std::vector<std::pair<std::string, int>> splits = {{"train", 8}, {"val", 1}, {"test", 1}};
  for (const auto& [split, count] : splits) {
    fs::create_directories(scene / split);
    io::Json frames = io::Json::array();
    for (int k = 0; k < count; ++k) {
      const std::string name = split + "/r_" + std::to_string(k);
      io::write_png8((scene / (name + ".png")).string(), size, size, 4, transparent.data());
      const double angle = 0.8 * k + (split == "train" ? 0.0 : 0.4);
      const auto pose = data::look_at_pose({4.0 * std::cos(angle), 4.0 * std::sin(angle), 1.5}, {0, 0, 0}, {0, 0, 1});
      frames.push_back({{"file_path", "./" + name}, {"transform_matrix", data::pose_to_json(pose)}});
    }
    io::write_json((scene / ("transforms_" + split + ".json")).string(),
                   {{"camera_angle_x", 0.69}, {"near", 2.0}, {"far", 6.0}, {"frames", frames}});
  }
  const std::string out = test::fresh_run_dir("background");
  train::Trainer trainer(ctx, tiny({{"steps", "500"}, {"batch_size", "64"}, {"checkpoint_every", "500"}}),
                         scene.string(), out, false);
  REQUIRE(trainer.config().background == Background::white);
  std::vector<double> losses;
  bool psnr_nan = false;
  train::TrainHooks hooks;
  hooks.on_step = [&](const train::StepReport& r) {
    losses.push_back(r.loss);
    psnr_nan = psnr_nan || std::isnan(r.psnr);
  };
  const auto result = trainer.run(hooks);
  CHECK(result.last_step == 500);
  CHECK(result.skipped_steps == 0);  // a skipped step is a non-finite loss or gradient
  REQUIRE(losses.size() == 500);
  for (double l : losses) REQUIRE(std::isfinite(l));
  CHECK_FALSE(psnr_nan);
  MESSAGE("all-background scene: loss " << losses.front() << " at step 1, " << losses.back() << " at step 500 ("
                                        << result.train_seconds << " s)");
  CHECK(losses.back() < losses.front());  // it learns the empty scene
  for (auto& network : trainer.networks()) {
    for (float p : network->download_params()) REQUIRE(std::isfinite(p));
  }
  const auto checkpoint =
      io::read_checkpoint_file(train::checkpoint_path((fs::path(out) / "checkpoints").string(), 500));
  for (const char* moment : {"network0.adam_m", "network0.adam_v"}) {
    for (float x : checkpoint.tensor(moment, "checkpoint")) REQUIRE(std::isfinite(x));
  }
  const auto dataset = data::load_dataset(scene.string(), {});
  std::vector<mlp::Network*> networks;
  for (auto& n : trainer.networks()) networks.push_back(n.get());
  eval::ImageRenderer renderer(ctx, trainer.spec(), networks, dataset.split("val").cameras, 256);
  const auto image = renderer.render(0);
  REQUIRE(image.rgb.size() == 3u * size * size);
  for (float v : image.rgb) REQUIRE(std::isfinite(v));
  for (float d : image.depth) REQUIRE(std::isfinite(d));
  for (float a : image.acc) REQUIRE(std::isfinite(a));
  double worst = 0.0;
  for (float v : image.rgb) worst = std::max(worst, std::abs(1.0 - v));
  MESSAGE("render of the held-out view: largest |1 - rgb| " << worst);
  CHECK(worst < 1e-2);  // it rendered the empty scene: background everywhere (measured 2e-5)
  fs::remove_all(out);
  fs::remove_all(scene);
}

namespace {

// Every network's parameters and Adam state (moments and update count), downloaded: what a step may change.
struct TrainingState {
  std::vector<std::vector<float>> params;
  std::vector<mlp::AdamState> adam;
};

TrainingState training_state(train::Trainer& trainer) {
  TrainingState state;
  for (auto& network : trainer.networks()) state.params.push_back(network->download_params());
  for (const auto& optimiser : trainer.optimisers()) state.adam.push_back(optimiser->state());
  return state;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// Whether two states are equal bit for bit, naming the first tensor that differs in `first_difference`.
bool same_state(const TrainingState& a, const TrainingState& b, std::string& first_difference) {
  if (a.params.size() != b.params.size() || a.adam.size() != b.adam.size()) {
    first_difference = "the number of networks";
    return false;
  }
  for (size_t n = 0; n < a.params.size(); ++n) {
    const std::string net = "network " + std::to_string(n);
    if (!same_bits(a.params[n], b.params[n])) first_difference = net + " parameters";
    else if (!same_bits(a.adam[n].m, b.adam[n].m)) first_difference = net + " Adam first moments";
    else if (!same_bits(a.adam[n].v, b.adam[n].v)) first_difference = net + " Adam second moments";
    else if (a.adam[n].step != b.adam[n].step) first_difference = net + " Adam update count";
    else continue;
    return false;
  }
  return true;
}

}  // namespace

TEST_CASE("train: a NaN in the gradients skips that step, leaving weights and Adam state bit for bit, and goes on") {
  auto& ctx = test::test_context();
  const std::string out = test::fresh_run_dir("nan");
  train::Trainer trainer(ctx, tiny({{"steps", "6"}, {"batch_size", "64"}}), test::small_scene(), out, false);
  TrainingState before_bad_step, after_bad_step, after_next_step;
  train::TrainHooks hooks;
  hooks.after_backward = [&](int64_t step, std::vector<std::unique_ptr<mlp::Network>>& networks) {
    if (step != 3) return;
    before_bad_step = training_state(trainer);  // the state step 2 left: the bad step's update is not applied yet
    const float nan = std::numeric_limits<float>::quiet_NaN();
    networks[0]->grads().upload(ctx, &nan, 1, 17);
  };
  std::vector<bool> skipped;
  hooks.on_step = [&](const train::StepReport& r) {
    skipped.push_back(r.skipped);
    if (r.step == 3) after_bad_step = training_state(trainer);
    if (r.step == 4) after_next_step = training_state(trainer);
  };
  const auto result = trainer.run(hooks);
  CHECK(result.last_step == 6);
  CHECK(result.skipped_steps == 1);
  REQUIRE(skipped.size() == 6);
  CHECK(skipped == std::vector<bool>{false, false, true, false, false, false});
  REQUIRE(!before_bad_step.params.empty());
  std::string difference;
  CHECK_MESSAGE(same_state(before_bad_step, after_bad_step, difference), "the skipped step changed " << difference);
  // The check can fail: the next, good step changes the parameters and the moments, and counts one update more.
  CHECK_FALSE(same_state(after_bad_step, after_next_step, difference));
  CHECK(after_next_step.adam[0].step == after_bad_step.adam[0].step + 1);
  for (float p : trainer.networks()[0]->download_params()) REQUIRE(std::isfinite(p));
  fs::remove_all(out);
}

TEST_CASE("train: repeated non-finite steps stop the run and keep the last good checkpoint") {
  auto& ctx = test::test_context();
  const std::string out = test::fresh_run_dir("nan-stop");
  train::Trainer trainer(ctx, tiny({{"steps", "20"}, {"batch_size", "64"}, {"checkpoint_every", "2"},
                                    {"max_bad_steps", "3"}}),
                         test::small_scene(), out, false);
  train::TrainHooks hooks;
  hooks.after_backward = [&](int64_t step, std::vector<std::unique_ptr<mlp::Network>>& networks) {
    if (step < 5) return;
    const float inf = std::numeric_limits<float>::infinity();
    networks[0]->grads().upload(ctx, &inf, 1, 0);
  };
  CHECK_THROWS_WITH_AS(trainer.run(hooks), doctest::Contains("ckpt_000000004.mnck"), Error);
  const auto saved = train::list_checkpoints((fs::path(out) / "checkpoints").string());
  REQUIRE(!saved.empty());
  CHECK(saved.back().first == 4);
  const auto checkpoint = io::read_checkpoint_file(saved.back().second);
  for (float p : checkpoint.tensor("network0.params", "ckpt")) REQUIRE(std::isfinite(p));
  fs::remove_all(out);
}

TEST_CASE("train: every variant trains a few steps on multiscale data and renders") {
  auto& ctx = test::test_context();
  const std::string multiscale = (fs::path(test::small_scene()) / "multiscale").string();
  for (const auto& entry : train::variants()) {
    const std::string& variant = entry.first;  // INFO cannot capture a structured binding (C++17)
    INFO("variant " << variant);
    const std::string out = test::fresh_run_dir("variant-" + variant);
    std::map<std::string, std::string> settings{{"steps", "3"}, {"batch_size", "128"}};
    if (variant == "zipnerf") settings.insert({{"grid_max", "128"}, {"grid_hash_log2", "14"}});  // a test-sized grid
    train::Trainer trainer(ctx, tiny(settings, variant), multiscale, out, false);
    CHECK(trainer.spec().loss.multiscale == trainer.config().area_loss);
    const auto result = trainer.run();
    CHECK(result.skipped_steps == 0);
    CHECK(std::isfinite(result.final_psnr));
    const size_t expected_networks = trainer.config().single_mlp ? 1 : 2;
    CHECK(trainer.networks().size() == expected_networks);
    auto model = train::load_trained_model(ctx, train::find_checkpoint(out));
    CHECK(model.step == 3);
    const auto dataset = data::load_dataset(multiscale, {});
    CHECK(model.grids.size() == (trainer.config().variant == train::ModelFamily::zipnerf ? 1u : 0u));
    eval::ImageRenderer renderer(ctx, model.spec, model.network_pointers(), model.grid_pointers(),
                                 dataset.split("val").cameras, eval::RenderSettings{512, 1, 0});
    const auto image = renderer.render(1);  // the ×2 downsampled copy of the first val view
    CHECK(image.width == 16);
    for (float v : image.rgb) REQUIRE(std::isfinite(v));
    for (float d : image.depth) REQUIRE(std::isfinite(d));
    fs::remove_all(out);
  }
}

TEST_CASE("train: a forward-facing LLFF capture trains in NDC with cylinders and a black background, as its data calls for") {
  auto& ctx = test::test_context();
  const auto scene = test::fresh_temp_dir("llff-train");
  data::ForwardFacingOptions capture;
  capture.width_px = 128;  // images_4/: 32x24
  capture.samples_per_axis = 2;
  capture.threads = 2;
  data::write_forward_facing_scene(scene.string(), capture);

  const train::SceneEffects effects = train::scene_effects(scene.string(), 4);
  std::string line;
  auto settings = train::with_scene_effects(effects, {{"factor", "4"}, {"steps", "200"}, {"log_every", "50"}}, line);
  CHECK(line ==
        "scene: forward-facing LLFF → NDC rays, cylinders, black background, raw view directions, density noise 1");
  auto config = train::resolve_config("tiny", "mipnerf", settings);
  CHECK(config.ray_shape == RayShape::cylinder);
  CHECK(config.background == Background::black);
  CHECK_FALSE(config.unit_viewdirs);  // the official LLFF loader's viewdirs = rays.directions
  CHECK(config.density_noise == 1.0);  // llff.gin
  // An explicit setting wins, and the line says so.
  train::with_scene_effects(effects, {{"background", "white"}}, line);
  CHECK(line.find("(given explicitly, kept: background = white)") != std::string::npos);
  // Zip-NeRF on a forward-facing capture: the same effects, nothing unbounded (NDC is bounded already).
  const train::SceneEffects zip_effects = train::scene_effects(scene.string(), 4, train::ModelFamily::zipnerf);
  CHECK(zip_effects.zipnerf_settings.empty());
  CHECK(effects.mipnerf_settings.empty());
  CHECK(zip_effects.settings == effects.settings);

  const std::string out = test::fresh_run_dir("llff");
  train::Trainer trainer(ctx, config, scene.string(), out, false);
  CHECK(trainer.spec().rays.ray_shape == RayShape::cylinder);  // compiled in: NDC rays, cylinders
  CHECK_FALSE(trainer.spec().rays.unit_viewdirs);
  CHECK(trainer.spec().render.density_noise == 1.0f);
  const auto& camera = trainer.dataset().split("train").cameras[0];
  CHECK(camera.near == 0.0);
  CHECK(camera.far == 1.0);
  trainer.run();
  const auto val_options = train::load_options(config, scene.string(), {"val"});  // images_4/, NDC
  const double learnt = evaluate_val(ctx, trainer, scene.string(), val_options).mean_psnr;
  const double constant = constant_colour_val_psnr(scene.string(), train::load_options(config, scene.string(), {}));
  MESSAGE("forward-facing capture, 200 tiny steps in NDC: val PSNR " << learnt << " dB; best constant colour "
                                                                      << constant << " dB");
  CHECK(learnt > constant + 2.0);  // learnt the geometry, not only the mean colour
  fs::remove_all(out);
  fs::remove_all(scene);
}

TEST_CASE("train: memory planning picks a chunk that fits, and says what to lower when nothing does") {
  auto& ctx = test::test_context();
  const auto paper = train::resolve_config("paper", "mipnerf", {});
  const auto spec = train::make_graph_spec(paper, false);
  const auto plan = train::plan_memory(spec, ctx.device_info(), 4096, {}, 0, true);
  MESSAGE("paper preset on " << ctx.device_info().name << ": " << plan.describe());
  CHECK(plan.chunk_rays >= 1);
  CHECK(plan.total() <= plan.budget_bytes);
  CHECK(plan.largest_buffer <= ctx.device_info().max_alloc_bytes);
  CHECK_THROWS_WITH_AS(train::plan_memory(spec, ctx.device_info(), 4096, {}, 1u << 20, true),
                       doctest::Contains("lower chunk_rays"), Error);
  CHECK_THROWS_WITH_AS(train::plan_memory(spec, ctx.device_info(), 4096, {}, 1u << 20, false),
                       doctest::Contains("lower --chunk (render_chunk_rays)"), Error);
  auto small_device = ctx.device_info();
  small_device.global_mem_bytes = 1ull << 20;  // one ray of 2 × 128 samples through 8×256 needs more
  small_device.max_alloc_bytes = 256ull << 10;
  CHECK_THROWS_WITH_AS(train::plan_memory(spec, small_device, 4096, {}, 0, true),
                       doctest::Contains("lower batch_size, num_samples"), Error);
  // The fixed part names its largest owner's setting: the images, the batch arrays, the networks.
  const auto fixed = [](size_t data, size_t batch, size_t networks) {
    train::FixedBytes f;
    f.data = data;
    f.batch = batch;
    f.networks = networks;
    f.largest_buffer = std::max({data, batch, networks});
    return f;
  };
  CHECK_THROWS_WITH_AS(train::plan_memory(spec, small_device, 4096, fixed(1ull << 30, 1, 1), 0, true),
                       doctest::Contains("train at a lower resolution (factor"), Error);
  CHECK_THROWS_WITH_AS(train::plan_memory(spec, small_device, 4096, fixed(1, 1ull << 30, 1), 0, true),
                       doctest::Contains("lower batch_size"), Error);
  CHECK_THROWS_WITH_AS(train::plan_memory(spec, small_device, 4096, fixed(1, 1, 1ull << 30), 0, true),
                       doctest::Contains("lower mlp_width"), Error);
  // Within the budget, but one buffer (the split's pixels) beyond the allocation limit.
  auto big_budget = small_device;
  big_budget.global_mem_bytes = 1ull << 40;
  CHECK_THROWS_WITH_AS(train::plan_memory(spec, big_budget, 4096, fixed(1ull << 20, 1, 1), 0, true),
                       doctest::Contains("a single buffer of 1 MiB"), Error);
}

TEST_CASE("train: rays through random points of their pixels are reproducible and differ from centred rays") {
  auto& ctx = test::test_context();
  auto params_after = [&](bool jitter, const std::string& name) {
    const std::string out = test::fresh_run_dir(name);
    train::Trainer trainer(ctx, tiny({{"steps", "2"}, {"batch_size", "64"}, {"jitter_pixels", jitter ? "true" : "false"}}),
                           test::small_scene(), out, false);
    CHECK(trainer.spec().rays.jitter_subpixel == jitter);
    trainer.run();
    auto params = trainer.networks()[0]->download_params();
    fs::remove_all(out);
    return params;
  };
  const auto jittered = params_after(true, "jitter-a");
  CHECK(bitwise_equal(jittered, params_after(true, "jitter-b")));
  CHECK(!bitwise_equal(jittered, params_after(false, "centred")));
  for (float p : jittered) REQUIRE(std::isfinite(p));
}
