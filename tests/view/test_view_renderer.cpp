// The viewer's real renderer (view::ViewRenderer, not a test double) under what a browser and a hostile client do at
// once: renders, path starts, cancels and status polls from several threads. Run in the thread-sanitizer stage too
// (scripts/test.sh, `tsan`), where any data race fails it; here a double start of the path thread ended the process
// (std::terminate from assigning a joinable std::thread).
#include <doctest/doctest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "data/paths/camera_path.hpp"
#include "io/png.hpp"
#include "io/video.hpp"
#include "support/skip.hpp"
#include "support/temp_scene.hpp"
#include "support/test_context.hpp"
#include "train/config.hpp"
#include "train/trainer.hpp"
#include "view/view_renderer.hpp"

namespace fs = std::filesystem;
using namespace mipnerf;

namespace {

// A run folder of the tiny preset trained 4 steps on a 16x16 procedural scene: what `view` serves.
const std::string& tiny_run() {
  static const std::string run = [] {
    const std::string scene = test::write_temp_scene("view-scene", {16, 4, 1, 1, 2});
    const fs::path out = test::fresh_temp_dir("view-run");
    const auto config = train::resolve_config("tiny", "mipnerf", {{"steps", "4"}, {"batch_size", "64"}});
    train::Trainer trainer(test::test_context(), config, scene, out.string(), false);
    trainer.run();
    return out.string();
  }();
  return run;
}

const char* kCamera = R"({"frames": [{"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,4],[0,0,0,1]],
  "fl_x": 20, "fl_y": 20, "cx": 8, "cy": 8, "w": 16, "h": 16}]})";
const char* kKeyframes = R"({"frames": [
  {"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,4],[0,0,0,1]], "fl_x": 20, "fl_y": 20, "cx": 8, "cy": 8, "w": 16, "h": 16},
  {"transform_matrix": [[1,0,0,0.5],[0,1,0,0],[0,0,1,4],[0,0,0,1]], "fl_x": 20, "fl_y": 20, "cx": 8, "cy": 8, "w": 16, "h": 16}]})";

Camera page_camera() { return data::parse_camera_path(kCamera, "test camera", {}).front(); }

// A path of `frames` frames at 16x16 (H.264 wants even sizes).
view::PathRequest small_path(uint32_t frames = 3) {
  view::PathRequest request;
  request.keyframes = data::parse_camera_path(kKeyframes, "test keyframes", {});
  request.frames = frames;
  request.divisor = 1;
  return request;
}

std::string path_state(view::ViewRenderer& renderer) {
  switch (renderer.path_status().state) {
    case view::PathStatus::State::idle: return "idle";
    case view::PathStatus::State::rendering: return "rendering";
    case view::PathStatus::State::done: return "done";
    case view::PathStatus::State::failed: return "failed";
    case view::PathStatus::State::cancelled: return "cancelled";
  }
  return "unknown";
}

// Polls until no path renders (the path thread ended), at most `seconds`.
bool wait_for_path(view::ViewRenderer& renderer, double seconds) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < until) {
    const std::string state = path_state(renderer);
    if (state != "rendering") return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

}  // namespace

TEST_CASE("view renderer: path starts sent at once start one path, and the others are told busy") {
  view::ViewRendererOptions options;
  options.run_folder = tiny_run();
  view::ViewRenderer renderer(test::test_context(), options);
  for (int round = 0; round < 4; ++round) {
    CAPTURE(round);
    constexpr int kThreads = 4;
    std::atomic<int> ready{0};
    std::atomic<int> started{0}, busy{0}, other{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t) {
      threads.emplace_back([&] {
        // Every thread asks at the same moment: a double-click, or a script.
        ++ready;
        while (ready.load() < kThreads) std::this_thread::yield();
        // Long enough that no thread finds the first path already done (it is cancelled below).
        const view::PathReply reply = renderer.start_path(small_path(600));
        (reply.status == view::PathReply::Status::started ? started
         : reply.status == view::PathReply::Status::busy  ? busy
                                                          : other)++;
      });
    }
    for (auto& thread : threads) thread.join();
    CHECK(started.load() == 1);
    CHECK(busy.load() == kThreads - 1);
    CHECK(other.load() == 0);
    renderer.cancel_path();
    REQUIRE(wait_for_path(renderer, 120.0));
    CHECK(path_state(renderer) == "cancelled");
  }
}

TEST_CASE("view renderer: renders, path starts, cancels and status polls from several threads") {
  view::ViewRendererOptions options;
  options.run_folder = tiny_run();
  options.max_waiting = 2;
  view::ViewRenderer renderer(test::test_context(), options);
  std::atomic<bool> stop{false};
  std::atomic<uint64_t> generation{0};
  std::atomic<int> rendered{0}, paths_started{0}, bad{0};
  auto renders = [&] {
    while (!stop) {
      view::RenderRequest request;
      request.camera = page_camera();
      request.divisor = 2;
      request.generation = ++generation;
      const view::RenderReply reply = renderer.render(request);
      if (reply.status == view::RenderReply::Status::ok) {
        ++rendered;
        if (reply.png.empty() || reply.width != 8 || reply.height != 8) ++bad;
      } else if (reply.status == view::RenderReply::Status::bad_request ||
                 reply.status == view::RenderReply::Status::failed) {
        ++bad;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));  // a page's pace, so some renders complete
    }
  };
  // Path starts a page might send (a path every 100 ms is far more than a user clicks), so the device is free for
  // the renders between them.
  auto paths = [&] {
    while (!stop) {
      if (renderer.start_path(small_path()).status == view::PathReply::Status::started) ++paths_started;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  };
  auto cancels_and_polls = [&] {
    for (int i = 0; !stop; ++i) {
      if (i % 7 == 0) renderer.cancel_path();
      const std::string state = path_state(renderer);
      if (state != "idle" && state != "rendering" && state != "done" && state != "cancelled") ++bad;
      if (renderer.status().step != 4) ++bad;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  };
  std::vector<std::thread> threads;
  // One page's renders (its requests are numbered; two pages' numbers would supersede each other's), against paths
  // started from two threads and cancels and polls from two more.
  threads.emplace_back(renders);
  threads.emplace_back(paths);
  threads.emplace_back(paths);
  threads.emplace_back(cancels_and_polls);
  threads.emplace_back(cancels_and_polls);
  // Until each kind of work has happened a few times (or 60 s, which fails below).
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (std::chrono::steady_clock::now() < until && (rendered < 3 || paths_started < 3)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  stop = true;
  for (auto& thread : threads) thread.join();
  CHECK(bad.load() == 0);
  CHECK(rendered.load() >= 3);
  CHECK(paths_started.load() >= 3);
  REQUIRE(wait_for_path(renderer, 120.0));
  // The viewer still works as before: a free-camera render, then a whole path.
  view::RenderRequest request;
  request.camera = page_camera();
  request.generation = generation + 1;
  CHECK(renderer.render(request).status == view::RenderReply::Status::ok);
  REQUIRE(renderer.start_path(small_path()).status == view::PathReply::Status::started);
  REQUIRE(wait_for_path(renderer, 120.0));
  CHECK(path_state(renderer) == "done");
}

TEST_CASE("view renderer: a render reports its rays as it goes, and the last one's when none is under way") {
  view::ViewRendererOptions options;
  options.run_folder = tiny_run();
  options.chunk_rays = 64;  // 4 chunks for the 16x16 frame
  view::ViewRenderer renderer(test::test_context(), options);
  view::RenderRequest request;
  request.camera = page_camera();
  request.generation = 7;
  REQUIRE(renderer.render(request).status == view::RenderReply::Status::ok);
  const view::RenderProgress progress = renderer.render_progress();
  CHECK(progress.rendering == false);
  CHECK(progress.generation == 7);
  CHECK(progress.divisor == 1);
  CHECK(progress.done_rays == 256);
  CHECK(progress.total_rays == 256);
  CHECK(progress.seconds > 0.0);
  // Polled from another thread while renders run: always a whole object, done never above total.
  std::atomic<bool> stop{false};
  std::thread poller([&] {
    while (!stop) {
      const view::RenderProgress p = renderer.render_progress();
      CHECK(p.done_rays <= std::max<size_t>(p.total_rays, 256));
    }
  });
  for (int i = 0; i < 5; ++i) {
    request.generation = 8 + i;
    CHECK(renderer.render(request).status == view::RenderReply::Status::ok);
  }
  stop = true;
  poller.join();
}

namespace {

view::RenderReply render_view(view::ViewRenderer& renderer, uint64_t generation, int divisor = 1,
                              view::RenderOutput output = view::RenderOutput::rgb) {
  view::RenderRequest request;
  request.camera = page_camera();
  request.generation = generation;
  request.divisor = divisor;
  request.output = output;
  return renderer.render(request);
}

// A run trained `steps` steps on the tiny run's scene size, in a folder of its own.
std::string trained_run(const std::string& name, int steps) {
  const std::string scene = test::write_temp_scene(name + "-scene", {16, 4, 1, 1, 2});
  const fs::path out = test::fresh_temp_dir(name);
  const auto config =
      train::resolve_config("tiny", "mipnerf", {{"steps", std::to_string(steps)}, {"batch_size", "64"}});
  train::Trainer trainer(test::test_context(), config, scene, out.string(), false);
  trainer.run();
  return out.string();
}

}  // namespace

TEST_CASE("view renderer: one image renderer serves every request of a checkpoint, with the images of a fresh one") {
  view::ViewRendererOptions options;
  options.run_folder = tiny_run();
  view::ViewRenderer renderer(test::test_context(), options);
  CHECK(renderer.renderers_built() == 1);  // the warm-up's
  const view::RenderReply first = render_view(renderer, 1);
  const view::RenderReply smaller = render_view(renderer, 2, 2);
  const view::RenderReply depth = render_view(renderer, 3, 1, view::RenderOutput::depth);
  const view::RenderReply again = render_view(renderer, 4);
  REQUIRE(first.status == view::RenderReply::Status::ok);
  REQUIRE(again.status == view::RenderReply::Status::ok);
  CHECK(smaller.width == 8);
  CHECK(depth.png != first.png);
  CHECK(again.png == first.png);  // nothing of the 8x8 and depth renders between leaks into it
  CHECK(renderer.renderers_built() == 1);
  // After a path (which frees the renderer for its own) the next request builds one again, rendering alike.
  REQUIRE(renderer.start_path(small_path(2)).status == view::PathReply::Status::started);
  REQUIRE(wait_for_path(renderer, 120.0));
  CHECK(render_view(renderer, 5).png == first.png);
  CHECK(renderer.renderers_built() == 2);
}

TEST_CASE("view renderer: a newer checkpoint written while it serves gets a renderer of its own networks") {
  const std::string later = trained_run("view-run-later", 8);
  const fs::path run = test::fresh_temp_dir("view-run-followed");
  fs::copy(tiny_run(), run, fs::copy_options::recursive);
  view::ViewRendererOptions options;
  options.run_folder = run.string();
  view::ViewRenderer renderer(test::test_context(), options);
  const view::RenderReply before = render_view(renderer, 1);
  REQUIRE(before.status == view::RenderReply::Status::ok);
  CHECK(before.step == 4);
  // `train` writing a newer checkpoint into the run the viewer follows.
  for (const auto& entry : fs::directory_iterator(fs::path(later) / "checkpoints")) {
    fs::copy_file(entry.path(), run / "checkpoints" / entry.path().filename(), fs::copy_options::skip_existing);
  }
  const view::RenderReply after = render_view(renderer, 2);
  REQUIRE(after.status == view::RenderReply::Status::ok);
  CHECK(after.step == 8);
  CHECK(renderer.renderers_built() == 2);
  CHECK(renderer.status().step == 8);
  // The image of the newer networks: what a viewer started on that checkpoint renders.
  view::ViewRendererOptions fresh_options;
  fresh_options.run_folder = later;
  view::ViewRenderer fresh(test::test_context(), fresh_options);
  CHECK(render_view(fresh, 1).png == after.png);
  CHECK(after.png != before.png);
}

// The page's divisors are sizes for people: 1/3 of the keyframes' 16x16 is 5x5, and 1/8 of the LLFF flower's 504x378
// is 63x47, which H.264 in 4:2:0 cannot hold. Such a path renders one pixel smaller per odd side instead of failing
// (it was refused with "needs an even width and height", whatever the user picked).
TEST_CASE("view renderer: a path at a divisor that gives odd sides renders at the even size below, video and all") {
  if (!io::video_supported()) {  // without a video the frames keep the divisor's size
    test::skip_test("this build has no FFmpeg (install " + std::string(io::kVideoPackages) + ")");
    return;
  }
  view::ViewRendererOptions options;
  options.run_folder = tiny_run();
  view::ViewRenderer renderer(test::test_context(), options);
  view::PathRequest request = small_path(2);
  request.divisor = 3;
  const view::PathReply reply = renderer.start_path(request);
  REQUIRE_MESSAGE(reply.status == view::PathReply::Status::started, reply.message);
  REQUIRE(wait_for_path(renderer, 120.0));
  const view::PathStatus status = renderer.path_status();
  REQUIRE_MESSAGE(path_state(renderer) == "done", status.message);
  const io::PngSize size = io::read_png_size((fs::path(options.run_folder) / status.first_frame).string());
  CHECK(size.width == 4);
  CHECK(size.height == 4);
  CHECK(fs::file_size(fs::path(options.run_folder) / status.video) > 0);
}
