// Data-parallel training and sharded rendering under `mpirun -np 2`, through the real executable on PoCL (one
// thread per rank): the weights of N steps against the single-process run, exact resume, a killed rank, ranks that
// disagree, and sharded render / eval against the single-process outputs. Skipped, with a message, when this build
// has no MPI or mpirun is missing.
#include <doctest/doctest.h>

#include <sys/types.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <signal.h>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "io/checkpoint_file.hpp"
#include "eval/metrics.hpp"
#include "io/exr.hpp"
#include "io/png.hpp"
#include "io/video.hpp"
#include "support/child_process.hpp"
#include "support/run_checks.hpp"
#include "support/skip.hpp"
#include "support/train_fixtures.hpp"
#include "train/checkpoint.hpp"

using namespace mipnerf;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

constexpr int kSteps = 8;
constexpr const char* kMpirun = MIPNERF_MPIRUN_PATH;  // "" when CMake found none

bool mpi_available() {
#ifndef MIPNERF_TEST_HAVE_MPI
  test::skip_test("this build has no MPI (install libopenmpi-dev and openmpi-bin, then reconfigure)");
  return false;
#else
  if (std::strlen(kMpirun) == 0 || !fs::exists(kMpirun)) {
    test::skip_test("mpirun was not found when the build was configured (install openmpi-bin)");
    return false;
  }
  return true;
#endif
}

// The mipnerf-cl arguments every run of a test shares: 256 rays in 4 chunks of 64, so each of 2 ranks trains two
// whole chunks, and a checkpoint every 2 steps.
std::vector<std::string> train_args(const std::string& out, bool resume, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> argv = {"train",        "--data",       test::small_scene(), "--out",   out,
                                   "--preset",     "tiny",         "--steps",           std::to_string(kSteps),
                                   "--batch_size", "256",          "--chunk_rays",      "64",    "--checkpoint_every",
                                   "2",            "--val_views",  "1"};
  test::add_test_device(argv);
  if (resume) argv.push_back("--resume");
  argv.insert(argv.end(), extra.begin(), extra.end());
  return argv;
}

// One PoCL thread per process, so two ranks share the 2 cores as one process with 2 threads would; root may start
// mpirun in a container.
test::ChildOptions options_for(const std::string& log) {
  test::ChildOptions options;
  options.environment = {"POCL_MAX_PTHREAD_COUNT=1", "OMPI_ALLOW_RUN_AS_ROOT=1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1",
                         "OMPI_MCA_rmaps_base_oversubscribe=1"};
  options.output_file = log;
  return options;
}

std::vector<std::string> single(const std::vector<std::string>& args) {
  std::vector<std::string> argv = {MIPNERF_CLI_PATH};
  argv.insert(argv.end(), args.begin(), args.end());
  return argv;
}

std::vector<std::string> two_ranks(const std::vector<std::string>& args) {
  std::vector<std::string> argv = {kMpirun, "-np", "2", MIPNERF_CLI_PATH};
  argv.insert(argv.end(), args.begin(), args.end());
  return argv;
}

int run(const std::vector<std::string>& argv, const fs::path& log) {
  test::ChildProcess child(argv, options_for(log.string()));
  child.wait();
  return child.exit_code();
}

// The run's checkpoint after `step` (by default its last, kSteps).
io::CheckpointFile checkpoint_at(const fs::path& run_dir, int step = kSteps) {
  return io::read_checkpoint_file(train::checkpoint_path((run_dir / "checkpoints").string(), step));
}

// The pid of rank `rank` of the mipnerf-cl processes writing into `out` (from /proc), or -1.
pid_t rank_pid(int rank, const std::string& out) {
  const std::string wanted = "OMPI_COMM_WORLD_RANK=" + std::to_string(rank);
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::string cmdline = test::read_text(entry.path() / "cmdline"), environ_text = test::read_text(entry.path() / "environ");
    std::replace(cmdline.begin(), cmdline.end(), '\0', ' ');
    if (cmdline.rfind(MIPNERF_CLI_PATH, 0) != 0 || cmdline.find(out) == std::string::npos) continue;
    std::replace(environ_text.begin(), environ_text.end(), '\0', '\n');
    if (("\n" + environ_text).find("\n" + wanted + "\n") != std::string::npos) return std::stoi(name);
  }
  return -1;
}

// The val PSNR a run printed ("val PSNR 18.44 dB"), or NaN.
double printed_val_psnr(const std::string& log) {
  const size_t at = log.find("val PSNR ");
  return at == std::string::npos ? std::nan("") : std::stod(log.substr(at + 9));
}

}  // namespace

TEST_CASE("2 ranks train the single-process weights, within the summation-order bound") {
  if (!mpi_available()) return;
  const fs::path root = test::fresh_run_dir("mpi-equal");
  // One step each way (the shared arguments with --steps 1 and a checkpoint after it), then kSteps.
  const auto one_step = [](const fs::path& out) {
    std::vector<std::string> args = train_args(out.string(), false);
    for (size_t i = 0; i + 1 < args.size(); ++i) {
      if (args[i] == "--steps" || args[i] == "--checkpoint_every") args[i + 1] = "1";
    }
    return args;
  };
  REQUIRE_MESSAGE(run(single(one_step(root / "one_1")), root / "one_1.log") == 0, test::read_text(root / "one_1.log"));
  REQUIRE_MESSAGE(run(two_ranks(one_step(root / "two_1")), root / "two_1.log") == 0,
                  test::read_text(root / "two_1.log"));
  REQUIRE_MESSAGE(run(single(train_args((root / "one").string(), false)), root / "one.log") == 0,
                  test::read_text(root / "one.log"));
  REQUIRE_MESSAGE(run(two_ranks(train_args((root / "two").string(), false)), root / "two.log") == 0,
                  test::read_text(root / "two.log"));

  // After one step. Both runs start from the same weights and compute every chunk's terms the same way (the same
  // rays, kernels and blocks); what differs is the order in which the gradient's terms are added: one process adds
  // 16 of them (4 chunks x 2 levels x 2 threads) one after another into the network's gradient, two ranks add their
  // 8 each and then the two sums. A sum of n terms in another order differs by at most ~2(n − 1)·u·Σ|terms|
  // (u = 2^-24). Adam's first moment after one step is 0.1·g, computed the same way from either g, so its elements
  // differ by that much; with the terms of an element no larger than ~10x the tensor's largest |m| / 0.1, that is
  // ≤ 30·6e-8·10 ≈ 2e-5 of the largest |m|.
  const io::CheckpointFile one_1 = checkpoint_at(root / "one_1", 1), two_1 = checkpoint_at(root / "two_1", 1);
  const std::vector<float> m_one = one_1.tensor("network0.adam_m", "one process"),
                           m_two = two_1.tensor("network0.adam_m", "two ranks");
  REQUIRE(m_one.size() == m_two.size());
  double m_largest = 0.0;
  for (const float m : m_one) m_largest = std::max(m_largest, std::fabs(static_cast<double>(m)));
  REQUIRE(m_largest > 0.0);
  double m_difference = 0.0;
  for (size_t i = 0; i < m_one.size(); ++i) {
    m_difference = std::max(m_difference, std::fabs(static_cast<double>(m_one[i]) - m_two[i]));
  }
  MESSAGE("after one step, Adam's first moments differ by at most " << m_difference << " (largest |m| "
                                                                     << m_largest << ")");
  CHECK(m_difference <= 2e-5 * m_largest);
  // The weights after that step: Adam's update lr·m̂/(√v̂ + ε) is lr·sign(g) whatever |g| (≫ ε), so an element whose
  // summed gradient is within rounding of 0 may step either way in the two runs (by up to 2·lr), and every other
  // element steps the same: it may differ by a rounding of the update, a couple of ulps of the weight. So every weight
  // that differs by more than 2 ulps must be one whose |m| is within the summation-order bound's reach of 0 (here
  // 1e-3 of the largest, 50x the bound).
  const std::vector<float> w_one = one_1.tensor("network0.params", "one process"),
                           w_two = two_1.tensor("network0.params", "two ranks");
  REQUIRE(w_one.size() == m_one.size());
  size_t flipped = 0;
  for (size_t i = 0; i < w_one.size(); ++i) {
    const float w = std::fabs(w_one[i]);
    const double two_ulps = 2.0 * (std::nextafter(w, INFINITY) - w);
    if (std::fabs(static_cast<double>(w_one[i]) - w_two[i]) <= two_ulps) continue;
    ++flipped;
    CAPTURE(i);
    CHECK(std::fabs(m_one[i]) <= 1e-3 * m_largest);
  }
  MESSAGE(flipped << " of " << w_one.size() << " weights stepped differently after one step (their |m| near 0)");

  // After kSteps: the same number of Adam steps, one val score (rank 0's), and the same val PSNR within 0.01 dB:
  // the differences above compound (a weight stepped the other way gets other gradients after it), but stay far below
  // what shows in the images (the largest weight difference is printed).
  const io::CheckpointFile one = checkpoint_at(root / "one"), two = checkpoint_at(root / "two");
  CHECK(one.header.at("adam_steps") == two.header.at("adam_steps"));
  const std::vector<float> a = one.tensor("network0.params", "one process"),
                           b = two.tensor("network0.params", "two ranks");
  REQUIRE(a.size() == b.size());
  double largest = 0.0;
  for (size_t i = 0; i < a.size(); ++i) largest = std::max(largest, std::fabs(static_cast<double>(a[i]) - b[i]));
  MESSAGE("after " << kSteps << " steps the largest weight difference is " << largest);
  const std::string one_log = test::read_text(root / "one.log"), two_log = test::read_text(root / "two.log");
  const double psnr_one = printed_val_psnr(one_log), psnr_two = printed_val_psnr(two_log);
  REQUIRE(std::isfinite(psnr_one));
  REQUIRE(std::isfinite(psnr_two));
  CHECK(std::fabs(psnr_one - psnr_two) <= 0.01);
  // The val score each run printed: rank 0 alone reports.
  size_t reports = 0;
  for (size_t at = 0; (at = two_log.find("val PSNR", at)) != std::string::npos; ++at) ++reports;
  CHECK(reports == 1);
  fs::remove_all(root);
}

TEST_CASE("a killed rank stops the job with a message, the checkpoints verify, and --resume continues exactly") {
  if (!mpi_available()) return;
  const fs::path root = test::fresh_run_dir("mpi-kill");
  const fs::path straight = root / "straight", killed = root / "killed";
  REQUIRE_MESSAGE(run(two_ranks(train_args(straight.string(), false)), root / "straight.log") == 0,
                  test::read_text(root / "straight.log"));

  // The same run, slowed by a pause in every atomic write, and rank 1 killed once its step-2 checkpoint exists.
  test::ChildOptions slowed = options_for((root / "killed.log").string());
  slowed.environment.push_back("MIPNERF_TEST_PAUSE_IN_WRITE_MS=300");
  test::ChildProcess job(two_ranks(train_args(killed.string(), false)), slowed);
  const std::string first_checkpoint = train::checkpoint_path((killed / "checkpoints").string(), 2);
  const auto give_up = Clock::now() + std::chrono::seconds(120);
  while (!fs::exists(first_checkpoint) && !job.finished() && Clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  const pid_t rank1 = rank_pid(1, killed.string());
  REQUIRE_MESSAGE(rank1 > 0, test::read_text(root / "killed.log"));
  REQUIRE(::kill(rank1, SIGKILL) == 0);
  const auto killed_at = Clock::now();
  while (!job.finished() && Clock::now() < killed_at + std::chrono::seconds(60)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  REQUIRE_MESSAGE(job.finished(), "the other rank did not stop within 60 s of rank 1's death");
  const std::string output = test::read_text(root / "killed.log");
  INFO(output);
  CHECK(job.exit_code() != 0);
  CHECK(output.find("rank 1") != std::string::npos);  // mpirun names the rank that died
  // No partial file under a checkpoint's name, and the run did not finish.
  const auto listed = train::list_checkpoints((killed / "checkpoints").string());
  REQUIRE(!listed.empty());
  CHECK(listed.back().first < kSteps);
  for (const auto& [step, path] : listed) CHECK_NOTHROW(io::read_checkpoint_file(path));

  REQUIRE_MESSAGE(run(two_ranks(train_args(killed.string(), true)), root / "resumed.log") == 0,
                  test::read_text(root / "resumed.log"));
  const io::CheckpointFile a = checkpoint_at(straight), b = checkpoint_at(killed);
  // Two ranks sum in the same order every time (rank 0's share + rank 1's): bit-equal.
  for (const char* tensor : {"network0.params", "network0.adam_m", "network0.adam_v"}) {
    CHECK_MESSAGE(test::same_bits(a.tensor(tensor, "straight"), b.tensor(tensor, "resumed")), tensor);
  }
  fs::remove_all(root);
}

TEST_CASE("ranks started with different settings stop together with one message") {
  if (!mpi_available()) return;
  const fs::path root = test::fresh_run_dir("mpi-disagree");
  // MPMD: rank 1 gets another learning rate.
  std::vector<std::string> argv = {kMpirun, "-np", "1", MIPNERF_CLI_PATH};
  for (const auto& a : train_args((root / "run").string(), false)) argv.push_back(a);
  argv.insert(argv.end(), {":", "-np", "1", MIPNERF_CLI_PATH});
  for (const auto& a : train_args((root / "run").string(), false, {"--lr_init", "1e-3"})) argv.push_back(a);
  const int code = run(argv, root / "log");
  const std::string output = test::read_text(root / "log");
  INFO(output);
  CHECK(code != 0);
  CHECK(output.find("the ranks disagree on the training settings: rank(s) 1 differ from rank 0") != std::string::npos);
  // Said once (rank 0), and no checkpoint was written.
  CHECK(output.find("disagree") == output.rfind("disagree"));
  CHECK(train::list_checkpoints((root / "run" / "checkpoints").string()).empty());
  fs::remove_all(root);
}

TEST_CASE("sharded render and eval write what one process writes") {
  if (!mpi_available()) return;
  const fs::path root = test::fresh_run_dir("mpi-render");
  const std::string model = (root / "model").string();
  REQUIRE_MESSAGE(run(single(train_args(model, false)), root / "train.log") == 0, test::read_text(root / "train.log"));
  // 40x40 frames in chunks of 300 rays: 6 chunks, 3 per rank, the last one short.
  const std::vector<std::string> render = {"render", "--checkpoint", model, "--split", "test", "--views", "1",
                                           "--format", "both", "--size", "40x40", "--chunk", "300"};
  auto with_out = [](std::vector<std::string> args, const fs::path& out) {
    args.insert(args.end(), {"--out", out.string()});
    return args;
  };
  REQUIRE_MESSAGE(run(single(with_out(render, root / "r1")), root / "r1.log") == 0, test::read_text(root / "r1.log"));
  REQUIRE_MESSAGE(run(two_ranks(with_out(render, root / "r2")), root / "r2.log") == 0, test::read_text(root / "r2.log"));
  size_t frames = 0;
  for (const auto& entry : fs::directory_iterator(root / "r1")) {
    if (entry.path().extension() != ".exr") continue;
    ++frames;
    const io::ExrImage a = io::read_exr(entry.path().string());
    const io::ExrImage b = io::read_exr((root / "r2" / entry.path().filename()).string());
    CHECK(test::same_bits(a.rgb, b.rgb));
    CHECK(test::same_bits(a.depth, b.depth));
    CHECK(test::same_bits(a.acc, b.acc));
    const std::string png = entry.path().stem().string() + ".png";
    CHECK(test::read_text(root / "r1" / png) == test::read_text(root / "r2" / png));
  }
  CHECK(frames == 1);

  // --video under mpirun: every rank renders its share of each orbit frame, rank 0 encodes; the MP4 decodes to the
  // frames' count and each is within 35 dB of the PNG the same two-rank render wrote.
  if (io::video_supported()) {
    const fs::path video = root / "v2" / "orbit.mp4";
    const std::vector<std::string> orbit = {"render", "--checkpoint", model, "--path", "orbit", "--frames", "3",
                                            "--size", "40x40", "--chunk", "300", "--format", "png",
                                            "--video", video.string(), "--out", (root / "v2").string()};
    REQUIRE_MESSAGE(run(two_ranks(orbit), root / "v2.log") == 0, test::read_text(root / "v2.log"));
    const io::VideoFrames decoded = io::read_video_frames(video.string());
    REQUIRE(decoded.frames.size() == 3);
    for (int k = 0; k < 3; ++k) {
      const io::PngImage png = io::read_png((root / "v2" / ("frame_000" + std::to_string(k) + ".png")).string());
      std::vector<float> rgb;
      for (size_t i = 0; i < png.rgba.size(); ++i) {
        if (i % 4 != 3) rgb.push_back(png.rgba[i]);
      }
      const double db = eval::psnr({decoded.frames[k].data(), 40, 40, 3}, {rgb.data(), 40, 40, 3});
      MESSAGE("mpirun -np 2 --video, frame " << k << ": " << db << " dB against its PNG");
      CHECK(db >= 35.0);
    }
    for (const auto& entry : fs::directory_iterator(root / "v2")) {  // no partial file left beside it
      CHECK_MESSAGE(entry.path().extension() != ".tmp", entry.path().string());
    }
  } else {
    test::skip_test("this build has no FFmpeg: the MPI video check did not run");
  }

  const std::vector<std::string> eval = {"eval", "--checkpoint", model, "--split", "val", "--no-images",
                                         "--chunk", "300"};
  REQUIRE_MESSAGE(run(single(with_out(eval, root / "e1")), root / "e1.log") == 0, test::read_text(root / "e1.log"));
  REQUIRE_MESSAGE(run(two_ranks(with_out(eval, root / "e2")), root / "e2.log") == 0, test::read_text(root / "e2.log"));
  auto scores = [](const fs::path& metrics) {
    const auto json = nlohmann::json::parse(test::read_text(metrics));
    std::vector<double> psnr;
    for (const auto& image : json.at("images")) psnr.push_back(image.at("psnr").get<double>());
    return psnr;
  };
  const auto s1 = scores(root / "e1" / "metrics.json"), s2 = scores(root / "e2" / "metrics.json");
  CHECK(!s1.empty());
  CHECK(s1 == s2);
  fs::remove_all(root);
}

TEST_CASE("a --device list gives each local rank its entry, and a malformed list is one message") {
  if (!mpi_available()) return;
  const fs::path root = test::fresh_run_dir("mpi-devices");
  const char* chosen = std::getenv("MIPNERF_TEST_DEVICE");
  const std::string device = chosen != nullptr ? chosen : "0";
  auto train_on = [&](const std::string& list, const std::string& name) {
    std::vector<std::string> args = {"train", "--data", test::small_scene(), "--out", (root / name).string(),
                                     "--preset", "tiny", "--steps", "2", "--batch_size", "64", "--val_views", "1",
                                     "--device", list};
    return run(two_ranks(args), root / (name + ".log"));
  };
  CHECK_MESSAGE(train_on(device + "," + device, "listed") == 0, test::read_text(root / "listed.log"));
  CHECK(train_on(device + "," + device + ",", "empty") != 0);
  const std::string output = test::read_text(root / "empty.log");
  INFO(output);
  CHECK(output.find("an empty entry in the list") != std::string::npos);
  CHECK(output.find("an empty entry") == output.rfind("an empty entry"));  // said once
  fs::remove_all(root);
}

TEST_CASE("commands that do not share work between ranks refuse to run under mpirun, once") {
  if (!mpi_available()) return;
  const fs::path root = test::fresh_run_dir("mpi-single");
  const int code = run(two_ranks({"make-scene", (root / "scene").string()}), root / "log");
  const std::string output = test::read_text(root / "log");
  INFO(output);
  CHECK(code != 0);
  CHECK(output.find("mipnerf-cl make-scene runs as one process: start it without mpirun") != std::string::npos);
  CHECK(output.find("runs as one process") == output.rfind("runs as one process"));
  CHECK(!fs::exists(root / "scene"));
  fs::remove_all(root);
}
