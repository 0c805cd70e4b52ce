// Crash consistency of `mipnerf-cl train`, through the real executable: SIGKILL at random moments and inside
// checkpoint writes, resume after each, and the final model is bit-equal to an uninterrupted run's; a file-size
// limit hit while checkpointing stops the run with one line and leaves the previous checkpoint intact.
#include <doctest/doctest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>

#include "core/error.hpp"
#include "io/checkpoint_file.hpp"
#include "support/child_process.hpp"
#include "support/run_checks.hpp"
#include "support/train_fixtures.hpp"
#include "train/checkpoint.hpp"

using namespace mipnerf;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

constexpr int kSteps = 40;
// The pause halfway through every atomic write (MIPNERF_TEST_PAUSE_IN_WRITE_MS): the window a kill aims at.
constexpr int kPauseMs = 150;

// `mipnerf-cl train` on the training tests' scene: small, a checkpoint every 4 steps, every step logged.
std::vector<std::string> train_command(const std::string& out, bool resume, int steps = kSteps,
                                       const std::vector<std::string>& extra = {}) {
  std::vector<std::string> argv = {MIPNERF_CLI_PATH,   "train",        "--data", test::small_scene(), "--out", out,
                                   "--preset",         "tiny",         "--steps", std::to_string(steps),
                                   "--batch_size",     "64",           "--checkpoint_every", "4",
                                   "--keep_checkpoints", "3",          "--log_every", "1", "--val_views", "1"};
  test::add_test_device(argv);
  if (resume) argv.push_back("--resume");
  argv.insert(argv.end(), extra.begin(), extra.end());
  return argv;
}

test::ChildOptions with_pause(const std::string& output_file) {
  test::ChildOptions options;
  options.environment = {"MIPNERF_TEST_PAUSE_IN_WRITE_MS=" + std::to_string(kPauseMs)};
  options.output_file = output_file;
  return options;
}

// A checkpoint temporary (".ckpt_….mnck.<pid>.<n>.tmp") in `folder`, or "".
std::string checkpoint_temporary(const fs::path& folder) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(".ckpt_", 0) == 0 && name.size() > 4 && name.compare(name.size() - 4, 4, ".tmp") == 0) return name;
  }
  return "";
}

// Every file the listing takes for a checkpoint reads and verifies: a kill never left a partial one under a
// checkpoint's name.
void check_every_checkpoint_verifies(const fs::path& folder, const std::string& when) {
  for (const auto& [step, path] : train::list_checkpoints(folder.string())) {
    try {
      io::read_checkpoint_file(path);
    } catch (const Error& e) {
      FAIL_CHECK(when << ": " << e.what());
    }
  }
}

}  // namespace

TEST_CASE("reliability: SIGKILL at random moments and inside checkpoint writes, resumed each time, ends bit-equal") {
  const fs::path root = test::fresh_run_dir("kill");
  const fs::path reference = root / "reference", killed = root / "killed";
  const fs::path checkpoints = killed / "checkpoints";

  // The uninterrupted run, with the same pauses, also gives the run's length that random moments are drawn in.
  const auto start = Clock::now();
  test::ChildProcess straight(train_command(reference.string(), false), with_pause((root / "reference.log").string()));
  straight.wait();
  const double run_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  REQUIRE_MESSAGE(straight.exit_code() == 0, test::read_text(root / "reference.log"));

  const unsigned seed = std::random_device{}();
  MESSAGE("kill moments from seed " << seed << " within a run of " << run_seconds << " s");
  std::mt19937 random(seed);
  int kills = 0, kills_in_checkpoint_writes = 0;
  for (int attempt = 0; kills < 6 && attempt < 20; ++attempt) {
    const std::string log = (root / ("attempt" + std::to_string(attempt) + ".log")).string();
    test::ChildProcess run(train_command(killed.string(), true), with_pause(log));
    bool in_write = false;
    if (attempt % 2 == 0) {
      // A random moment of the run: start-up, a step, a log line, a checkpoint or config write, the val render.
      std::uniform_real_distribution<double> moment(0.05, 0.9 * run_seconds);
      std::this_thread::sleep_for(std::chrono::duration<double>(moment(random)));
    } else {
      // Inside a checkpoint write: as soon as a checkpoint temporary appears, a random moment into its pause.
      const auto give_up = Clock::now() + std::chrono::duration<double>(2 * run_seconds + 10);
      while (checkpoint_temporary(checkpoints).empty() && !run.finished() && Clock::now() < give_up) {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
      }
      std::uniform_int_distribution<int> into(0, kPauseMs / 2);
      std::this_thread::sleep_for(std::chrono::milliseconds(into(random)));
      in_write = !checkpoint_temporary(checkpoints).empty();
    }
    const bool was_killed = run.kill_now();
    const std::string output = test::read_text(log);
    INFO("attempt " << attempt << " output:\n" << output);
    if (!was_killed) {
      // It finished first: a complete run proves nothing about kills, so start the killed run over.
      REQUIRE(run.exit_code() == 0);
      fs::remove_all(killed);
      continue;
    }
    ++kills;
    kills_in_checkpoint_writes += in_write ? 1 : 0;
    CHECK(output.find("skipped") == std::string::npos);  // no checkpoint ever failed to verify
    check_every_checkpoint_verifies(checkpoints, "after kill " + std::to_string(kills));
  }
  REQUIRE(kills >= 6);
  CHECK(kills_in_checkpoint_writes >= 2);

  test::ChildProcess last(train_command(killed.string(), true), with_pause((root / "last.log").string()));
  last.wait();
  const std::string last_output = test::read_text(root / "last.log");
  INFO("the last run's output:\n" << last_output);
  REQUIRE(last.exit_code() == 0);

  // The final models: parameters, Adam moments and step counts bit for bit.
  const auto a = io::read_checkpoint_file(train::checkpoint_path((reference / "checkpoints").string(), kSteps));
  const auto b = io::read_checkpoint_file(train::checkpoint_path(checkpoints.string(), kSteps));
  for (const char* tensor : {"network0.params", "network0.adam_m", "network0.adam_v"}) {
    CHECK_MESSAGE(test::same_bits(a.tensor(tensor, "reference"), b.tensor(tensor, "killed")), tensor);
  }
  CHECK(a.header.at("adam_steps") == b.header.at("adam_steps"));
  // Nothing half-written is left, and the log has every step once, in order.
  CHECK(checkpoint_temporary(checkpoints).empty());
  for (const auto& entry : fs::directory_iterator(checkpoints)) CHECK(entry.path().extension() != ".corrupt");
  std::ifstream csv(killed / "train_log.csv");
  std::string line;
  std::getline(csv, line);
  int expected_step = 1;
  while (std::getline(csv, line)) CHECK(std::stoi(line.substr(0, line.find(','))) == expected_step++);
  CHECK(expected_step == kSteps + 1);
  CHECK(nlohmann::json::parse(test::read_text(killed / "summary.json")).is_object());
  fs::remove_all(root);
}

TEST_CASE("reliability: a file-size limit hit while checkpointing stops the run with one line, and the last checkpoint stays") {
  const fs::path root = test::fresh_run_dir("full-disk"), out = root / "run";
  // A 256-wide network, so that a checkpoint (3.6 MB) outgrows every other file the run writes, PoCL's included:
  // each program build writes its preprocessed source (1–2 MB) to the kernel cache, even when cached.
  const std::vector<std::string> wide = {"--mlp_width", "256"};
  {
    test::ChildProcess first(train_command(out.string(), false, 8, wide),
                             {{}, (root / "first.log").string(), -1});
    REQUIRE(first.wait() == 0);
  }
  const std::string kept = train::checkpoint_path((out / "checkpoints").string(), 8);
  const auto before = io::read_checkpoint_file(kept);
  const auto checkpoint_bytes = static_cast<long long>(fs::file_size(kept));
  REQUIRE(checkpoint_bytes > 3'000'000);

  // A limit just below one checkpoint's size: the run trains on to step 12, then its checkpoint write fails (EFBIG,
  // what a full disk gives as ENOSPC).
  const std::string log = (root / "limited.log").string();
  test::ChildOptions limited{{}, log, checkpoint_bytes - 256 * 1024};
  test::ChildProcess second(train_command(out.string(), true, 16, wide), limited);
  const int status = second.wait();
  const std::string output = test::read_text(log);
  INFO(output);
  REQUIRE(WIFEXITED(status));  // not killed by a signal (SIGXFSZ ignored, the error handled)
  CHECK(WEXITSTATUS(status) != 0);
  CHECK(output.find("ckpt_000000012.mnck: write failed (File too large)") != std::string::npos);
  CHECK(output.find(kept + " is intact") != std::string::npos);
  CHECK(!fs::exists(train::checkpoint_path((out / "checkpoints").string(), 12)));
  CHECK(checkpoint_temporary(out / "checkpoints").empty());
  const auto after = io::read_checkpoint_file(kept);
  CHECK(test::same_bits(after.tensor("network0.params", "after"), before.tensor("network0.params", "before")));
  fs::remove_all(root);
}

namespace {

// Output into `log`, no pauses in writes.
test::ChildOptions logged_to(const fs::path& log) {
  test::ChildOptions options;
  options.output_file = log.string();
  return options;
}

// Runs `argv` (mipnerf-cl and its arguments, on the test device) to its end; its exit code, its output in `log`.
int run_to_end(std::vector<std::string> argv, const fs::path& log) {
  test::add_test_device(argv);
  test::ChildProcess child(argv, logged_to(log));
  child.wait();
  return child.exit_code();
}

// Starts `argv` and kills it (SIGKILL) once its first checkpoint is in `checkpoints`: a run interrupted for good, as
// a closed laptop would leave it. False when it ended before a checkpoint appeared (nothing was interrupted).
bool kill_after_first_checkpoint(std::vector<std::string> argv, const fs::path& checkpoints, const fs::path& log) {
  test::add_test_device(argv);
  test::ChildProcess child(argv, logged_to(log));
  const auto give_up = Clock::now() + std::chrono::seconds(120);
  while (train::list_checkpoints(checkpoints.string()).empty() && !child.finished() && Clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return child.kill_now();
}

void check_same_final_model(const fs::path& a_run, const fs::path& b_run, int steps) {
  const auto a = io::read_checkpoint_file(train::checkpoint_path((a_run / "checkpoints").string(), steps));
  const auto b = io::read_checkpoint_file(train::checkpoint_path((b_run / "checkpoints").string(), steps));
  for (const char* tensor : {"network0.params", "network0.adam_m", "network0.adam_v"}) {
    CHECK_MESSAGE(test::same_bits(a.tensor(tensor, "uninterrupted"), b.tensor(tensor, "resumed")), tensor);
  }
  CHECK(a.header.at("adam_steps") == b.header.at("adam_steps"));
}

}  // namespace

// `train --out RUN --resume` and nothing else continues the run RUN holds: its data and settings come from its
// checkpoint (no --data: the built-in scene is not generated again; an LLFF capture keeps NDC, cylinders, black),
// and the result is bit-equal to an uninterrupted run's. Given other data, it refuses in one line; on a finished run
// it says so.
TEST_CASE("reliability: train --out RUN --resume alone continues a killed run bit for bit, procedural and LLFF") {
  const fs::path root = test::fresh_run_dir("resume-out");
  const std::string cli = MIPNERF_CLI_PATH;
  const std::vector<std::string> small = {"--preset", "tiny", "--steps", "24", "--batch_size", "64",
                                          "--checkpoint_every", "4", "--log_every", "1", "--val_views", "1"};
  auto train = [&](const fs::path& out, std::vector<std::string> data) {
    std::vector<std::string> argv = {cli, "train", "--out", out.string()};
    argv.insert(argv.end(), data.begin(), data.end());
    argv.insert(argv.end(), small.begin(), small.end());
    return argv;
  };
  // A forward-facing LLFF capture (NDC rays, cylinders, a black background, density noise), made by make-scene.
  const fs::path llff = root / "llff";
  REQUIRE(run_to_end({cli, "make-scene", llff.string(), "--forward-facing", "--size", "48", "--samples", "1"},
                     root / "make-scene.log") == 0);
  struct Case {
    const char* name;
    std::vector<std::string> data;  // empty: the built-in procedural scene, made in OUT/scene
  };
  for (const Case& c : {Case{"procedural", {}}, Case{"llff", {"--data", llff.string(), "--factor", "4"}}}) {
    CAPTURE(c.name);
    const fs::path reference = root / (std::string(c.name) + "-reference"), killed = root / (std::string(c.name) + "-killed");
    REQUIRE_MESSAGE(run_to_end(train(reference, c.data), root / "reference.log") == 0,
                    test::read_text(root / "reference.log"));
    REQUIRE(kill_after_first_checkpoint(train(killed, c.data), killed / "checkpoints", root / "killed.log"));
    const auto scene_files_before = fs::exists(killed / "scene");
    // The resume names nothing but the run.
    const fs::path resumed_log = root / (std::string(c.name) + "-resumed.log");
    REQUIRE_MESSAGE(run_to_end({cli, "train", "--out", killed.string(), "--resume"}, resumed_log) == 0,
                    test::read_text(resumed_log));
    const std::string resumed = test::read_text(resumed_log);
    CHECK(resumed.find("generating the built-in procedural scene") == std::string::npos);
    CHECK(fs::exists(killed / "scene") == scene_files_before);  // nothing new in the run folder
    CHECK(resumed.find("trained 24 steps") != std::string::npos);
    check_same_final_model(reference, killed, 24);
    // Finished: it says so, and trains nothing.
    const fs::path again_log = root / (std::string(c.name) + "-again.log");
    REQUIRE(run_to_end({cli, "train", "--out", killed.string(), "--resume"}, again_log) == 0);
    CHECK(test::read_text(again_log).find("is already at step 24 of 24: nothing to train") != std::string::npos);
    // Killed after its last checkpoint, while scoring its val views: no summary.json. The resume scores them (the
    // reference's scores), where it used to say "already at step 24" and point to a file that did not exist.
    fs::remove(killed / "summary.json");
    const fs::path scoring_log = root / (std::string(c.name) + "-scoring.log");
    REQUIRE(run_to_end({cli, "train", "--out", killed.string(), "--resume"}, scoring_log) == 0);
    const std::string scoring = test::read_text(scoring_log);
    INFO(scoring);
    CHECK(scoring.find("is at step 24 of 24 but its val scores were never written") != std::string::npos);
    REQUIRE(fs::exists(killed / "summary.json"));
    const auto val_psnr = [](const fs::path& run) {
      return nlohmann::json::parse(test::read_text(run / "summary.json")).at("val").at("mean_psnr").get<double>();
    };
    CHECK(val_psnr(killed) == val_psnr(reference));
  }
  // Other data (by content, whatever its name): refused in one line, the run left as it was.
  const fs::path refused_log = root / "refused.log";
  const std::vector<std::string> other = {cli,      "train", "--out", (root / "procedural-killed").string(), "--resume",
                                          "--data", llff.string(), "--factor", "4", "--steps", "30"};
  CHECK(run_to_end(other, refused_log) == 1);
  const std::string refused = test::read_text(refused_log);
  CHECK(refused.find("is not the data this run trained on until step 24") != std::string::npos);
  CHECK(std::count(refused.begin(), refused.end(), '\n') == 1);
  CHECK(train::list_checkpoints((root / "procedural-killed/checkpoints").string()).back().first == 24);
  fs::remove_all(root);
}
