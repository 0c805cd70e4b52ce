// H.264 MP4 video (host/io/video): synthetic frames written and decoded back at ≥ 35 dB each, with the frame count,
// size, rate, codec and pixel format the writer promised; the index before the frames (+faststart); atomic output
// (no file until finish, no temporary left); one-line errors naming the file for bad settings, odd sizes, unwritable
// folders and files that are not videos.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "io/video.hpp"
#include "support/data_fixtures.hpp"
#include "support/skip.hpp"

using namespace mipnerf;
using test::contains;
using test::error_of;
namespace fs = std::filesystem;

namespace {

// Frame `t` of a synthetic clip, [h][w][3] in [0, 1]: smooth colour ramps, a soft disc that moves with t, and fine
// grey stripes of low contrast (brightness detail, which 4:2:0 keeps at full resolution; colour detail finer than
// 2 pixels it halves by design); values a little outside [0, 1] and one NaN, which the writer clamps (and zeroes) as
// the PNG writer does.
std::vector<float> synthetic_frame(uint32_t w, uint32_t h, int t) {
  std::vector<float> rgb(static_cast<size_t>(w) * h * 3);
  const double cx = 0.3 * w + 2.0 * t, cy = 0.5 * h, radius = 0.2 * h;
  for (uint32_t y = 0; y < h; ++y) {
    for (uint32_t x = 0; x < w; ++x) {
      const double u = (x + 0.5) / w, v = (y + 0.5) / h;
      const double d = std::hypot(x + 0.5 - cx, y + 0.5 - cy);
      const double disc = 1.0 / (1.0 + std::exp((d - radius) / 1.5));  // an edge ~3 pixels wide
      const double stripes = 0.04 * std::sin(y * 1.3);
      float* p = &rgb[(static_cast<size_t>(y) * w + x) * 3];
      p[0] = static_cast<float>(0.1 + 0.8 * u + 0.3 * disc + stripes);
      p[1] = static_cast<float>(0.2 + 0.6 * v * (1.0 - disc) + stripes);
      p[2] = static_cast<float>(0.75 - 0.7 * u * v + 0.1 * disc + stripes);
    }
  }
  rgb[0] = -0.2f;
  rgb[4] = 1.3f;
  rgb[8] = std::nanf("");
  return rgb;
}

// What the writer encodes: each sample as the PNG writer quantises it (NaN → 0, clamped, nearest of 0..255).
std::vector<float> quantised(const std::vector<float>& rgb) {
  std::vector<float> out(rgb.size());
  for (size_t i = 0; i < rgb.size(); ++i) {
    const double unit = std::isnan(rgb[i]) ? 0.0 : std::fmin(std::fmax(rgb[i], 0.0), 1.0);
    out[i] = static_cast<float>(std::lround(unit * 255.0)) / 255.0f;
  }
  return out;
}

// PSNR over all pixels and channels, data range 1 (eval/metrics computes it the same way).
double psnr(const std::vector<float>& a, const std::vector<float>& b) {
  double sum = 0.0;
  for (size_t i = 0; i < a.size(); ++i) sum += (static_cast<double>(a[i]) - b[i]) * (static_cast<double>(a[i]) - b[i]);
  return -10.0 * std::log10(sum / static_cast<double>(a.size()));
}

size_t entries(const std::string& folder) {
  return static_cast<size_t>(std::distance(fs::directory_iterator(folder), fs::directory_iterator{}));
}

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

TEST_CASE("video: synthetic frames come back from the MP4 at 35 dB or more each, with their count, size and rate") {
  if (!io::video_supported()) {
    test::skip_test("this build has no FFmpeg (install " + std::string(io::kVideoPackages) + ")");
    return;
  }
  test::TempDir dir;
  const std::string path = dir / "clip.mp4";
  const uint32_t w = 64, h = 48;
  const int count = 7;
  std::vector<std::vector<float>> sent;
  {
    io::VideoWriter writer(path, w, h, 30.0, 18);
    for (int t = 0; t < count; ++t) {
      sent.push_back(synthetic_frame(w, h, t));
      writer.add_frame(sent.back().data());
    }
    CHECK(writer.frames() == size_t(count));
    CHECK_FALSE(fs::exists(path));  // encoded under a temporary name until finish()
    writer.finish();
  }
  CHECK(entries(dir.path()) == 1);  // the video, and no temporary left beside it

  const io::VideoFrames video = io::read_video_frames(path);
  CHECK(video.codec == "h264");
  CHECK(video.pixel_format == "yuv420p");
  CHECK(video.width == w);
  CHECK(video.height == h);
  CHECK(video.fps == doctest::Approx(30.0).epsilon(1e-9));
  REQUIRE(video.frames.size() == size_t(count));
  for (int t = 0; t < count; ++t) {
    REQUIRE(video.frames[t].size() == size_t(w) * h * 3);
    const double db = psnr(video.frames[t], quantised(sent[t]));
    MESSAGE("frame " << t << ": " << db << " dB");
    CHECK(db >= 35.0);
  }
  // +faststart: the index (moov) comes before the frames (mdat), so a player starts before the download ends.
  const std::string bytes = read_bytes(path);
  CHECK(bytes.substr(4, 4) == "ftyp");
  REQUIRE(bytes.find("moov") != std::string::npos);
  CHECK(bytes.find("moov") < bytes.find("mdat"));
}

TEST_CASE("video: frame rates other than 30 are kept, and a lower CRF gives a closer picture") {
  if (!io::video_supported()) {
    test::skip_test("this build has no FFmpeg");
    return;
  }
  test::TempDir dir;
  const uint32_t w = 32, h = 32;
  auto write = [&](const std::string& name, double fps, int crf) {
    io::VideoWriter writer(dir / name, w, h, fps, crf);
    for (int t = 0; t < 3; ++t) writer.add_frame(synthetic_frame(w, h, t).data());
    writer.finish();
    return io::read_video_frames(dir / name);
  };
  const auto ntsc = write("ntsc.mp4", 30000.0 / 1001.0, 18);
  CHECK(ntsc.fps == doctest::Approx(30000.0 / 1001.0).epsilon(1e-6));
  const auto slow = write("slow.mp4", 2.5, 18);
  CHECK(slow.fps == doctest::Approx(2.5).epsilon(1e-9));
  const auto fine = write("fine.mp4", 24.0, 0);  // lossless in YUV: only the conversion's rounding and 4:2:0 remain
  const auto coarse = write("coarse.mp4", 24.0, 45);
  REQUIRE(fine.frames.size() == 3);
  REQUIRE(coarse.frames.size() == 3);
  const auto truth = quantised(synthetic_frame(w, h, 1));
  CHECK(psnr(fine.frames[1], truth) > psnr(coarse.frames[1], truth));
}

TEST_CASE("video: bad settings, odd sizes, unwritable folders and unfinished writers") {
  test::TempDir dir;
  const std::string path = dir / "v.mp4";
  // Settings and sizes are checked without FFmpeg too.
  CHECK(contains(error_of([&] { io::check_video_settings(path, 0.0, 18); }),
                 "v.mp4: 0 frames per second: the frame rate must lie in (0, 1000]"));
  CHECK(contains(error_of([&] { io::check_video_settings(path, -5.0, 18); }), "-5 frames per second"));
  CHECK(contains(error_of([&] { io::check_video_settings(path, std::nan(""), 18); }), "frames per second"));
  CHECK(contains(error_of([&] { io::check_video_settings(path, 30.0, -1); }),
                 "v.mp4: CRF -1: libx264's constant "
                 "rate factor lies in 0..51"));
  CHECK(contains(error_of([&] { io::check_video_settings(path, 30.0, 52); }), "CRF 52"));
  CHECK(error_of([&] { io::check_video_settings(path, 60.0, 51); }).empty());
  CHECK(contains(error_of([&] { io::check_video_frame_size(path, 25, 24); }),
                 "v.mp4: frames of 25x24 pixels: H.264 video in 4:2:0 (yuv420p) needs an even width and height; "
                 "render at an even size, e.g. 26x24"));
  CHECK(contains(error_of([&] { io::check_video_frame_size(path, 1, 1); }), "e.g. 2x2"));
  CHECK(error_of([&] { io::check_video_frame_size(path, 2, 2); }).empty());

  if (!io::video_supported()) {
    const std::string error = error_of([&] { io::check_video_path(path); });
    CHECK(contains(error, "built without FFmpeg"));
    CHECK(contains(error, io::kVideoPackages));
    CHECK(contains(error_of([&] { io::VideoWriter writer(path, 16, 16, 30.0, 18); }), io::kVideoPackages));
    return;
  }
  CHECK(contains(error_of([&] { io::check_video_path(dir / "v.avi"); }),
                 "v.avi: a video is written as H.264 in an MP4 file: give a file name ending in .mp4"));
  fs::create_directories(dir / "folder.mp4");
  CHECK(contains(error_of([&] { io::check_video_path(dir / "folder.mp4"); }), "folder.mp4: is a folder"));
  { std::ofstream(dir / "blocker") << "a file where a folder should be"; }
  CHECK(contains(error_of([&] { io::check_video_path(dir / "blocker/v.mp4"); }),
                 "blocker/v.mp4: cannot create its folder"));
  CHECK(error_of([&] { io::check_video_path(dir / "new/folder/v.MP4"); }).empty());
  CHECK(fs::is_directory(dir / "new/folder"));
  CHECK(entries(dir / "new/folder") == 0);  // the probe is gone

  // The writer checks what the checks check, naming the file.
  CHECK(contains(error_of([&] { io::VideoWriter writer(path, 25, 24, 30.0, 18); }), "v.mp4: frames of 25x24"));
  CHECK(contains(error_of([&] { io::VideoWriter writer(path, 16, 16, 30.0, 60); }), "v.mp4: CRF 60"));
  CHECK(contains(error_of([&] { io::VideoWriter writer(dir / "blocker/v.mp4", 16, 16, 30.0, 18); }),
                 "cannot create its folder"));
  // Unfinished: no video and no temporary; finish() without a frame refuses.
  const size_t before = entries(dir.path());
  {
    io::VideoWriter writer(path, 16, 16, 30.0, 18);
    writer.add_frame(synthetic_frame(16, 16, 0).data());
  }
  CHECK_FALSE(fs::exists(path));
  CHECK(entries(dir.path()) == before);
  {
    io::VideoWriter writer(path, 16, 16, 30.0, 18);
    CHECK(contains(error_of([&] { writer.finish(); }), "v.mp4: a video needs at least one frame"));
  }
  CHECK(entries(dir.path()) == before);
}

TEST_CASE("video: reading what is not a video names the file and libav's reason") {
  if (!io::video_supported()) {
    test::skip_test("this build has no FFmpeg");
    return;
  }
  test::TempDir dir;
  const std::string missing = dir / "missing.mp4";
  const std::string error = error_of([&] { io::read_video_frames(missing); });
  CHECK(contains(error, "missing.mp4: opening the video failed: No such file or directory"));
  { std::ofstream(dir / "text.mp4") << "not a video at all\n"; }
  const std::string garbage = error_of([&] { io::read_video_frames(dir / "text.mp4"); });
  CHECK(contains(garbage, "text.mp4: "));
  CHECK(contains(garbage, " failed: "));
  CHECK(garbage.find('\n') == std::string::npos);
}
