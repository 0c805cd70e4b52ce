// `mipnerf-cl render --video` through the real executable, from the tests' trained checkpoint (render_fixtures.hpp):
// the MP4 decodes to as many frames as the orbit has, each within 35 dB of the PNG the same render wrote; render.json
// names the video; --format none writes the video and the records but no image.
#include <doctest/doctest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "eval/metrics.hpp"
#include "io/json.hpp"
#include "io/png.hpp"
#include "io/video.hpp"
#include "render_fixtures.hpp"
#include "support/skip.hpp"

using namespace mipnerf;
namespace fs = std::filesystem;

namespace {

std::vector<float> rgb_of(const io::PngImage& png) {
  std::vector<float> rgb;
  rgb.reserve(static_cast<size_t>(png.width) * png.height * 3);
  for (size_t i = 0; i < png.rgba.size(); ++i) {
    if (i % 4 != 3) rgb.push_back(png.rgba[i]);
  }
  return rgb;
}

double psnr(const std::vector<float>& a, const std::vector<float>& b, uint32_t width, uint32_t height) {
  return eval::psnr({a.data(), height, width, 3}, {b.data(), height, width, 3});
}

std::string frame_stem(int k) { return "frame_000" + std::to_string(k); }

}  // namespace

TEST_CASE("render: --video writes an MP4 whose every frame is within 35 dB of the PNG of the same frame") {
  if (!io::video_supported()) {
    test::skip_test("this build has no FFmpeg (install " + std::string(io::kVideoPackages) + ")");
    return;
  }
  const std::string out = test::fresh_temp_dir("render-cli-video").string();
  const std::string video = out + "/movie/orbit.mp4";  // its folder is made
  auto result =
      test::run_cli("render --checkpoint " + test::trained_checkpoint() +
                    " --path orbit --frames 4 --size 48x32 --format png --video " + video + " --fps 12 --out " + out);
  INFO(result.err);
  REQUIRE(result.exit_code == 0);
  CHECK(result.out.find("rendered 4 frames of an orbit (48x32)") != std::string::npos);
  CHECK(result.out.find("images in " + out + "; video in " + video + " (12 fps)") != std::string::npos);

  const io::VideoFrames decoded = io::read_video_frames(video);
  CHECK(decoded.codec == "h264");
  CHECK(decoded.pixel_format == "yuv420p");
  CHECK(decoded.fps == doctest::Approx(12.0).epsilon(1e-9));
  REQUIRE(decoded.width == 48);
  REQUIRE(decoded.height == 32);
  REQUIRE(decoded.frames.size() == 4);
  for (int k = 0; k < 4; ++k) {
    const io::PngImage png = io::read_png(out + "/" + frame_stem(k) + ".png");
    REQUIRE(png.width == 48);
    const double db = psnr(decoded.frames[k], rgb_of(png), 48, 32);
    MESSAGE("frame " << k << ": decoded video vs PNG " << db << " dB");
    CHECK(db >= 35.0);
  }
  const io::Json record = io::read_json(out + "/render.json");
  CHECK(record["formats"] == "png");
  REQUIRE(record.contains("video"));
  CHECK(record["video"]["file"] == fs::absolute(video).lexically_normal().string());
  CHECK(record["video"]["frames"] == 4);
  CHECK(record["video"]["fps"] == 12.0);
  CHECK(record["video"]["crf"] == 18);
  CHECK(record["video"]["width"] == 48);

  // --format none: the video, transforms.json and render.json, and no image; the frames are the same renders.
  const std::string only = test::fresh_temp_dir("render-cli-video-only").string();
  result = test::run_cli("render --checkpoint " + test::trained_checkpoint() +
                         " --path orbit --frames 4 --size 48x32 --format none --crf 10 --video " + only +
                         "/orbit.mp4 --out " + only);
  INFO(result.err);
  REQUIRE(result.exit_code == 0);
  CHECK(result.out.find("records in " + only + "; video in ") != std::string::npos);
  for (const auto& entry : fs::directory_iterator(only)) {
    const std::string ext = entry.path().extension().string();
    CHECK_MESSAGE((ext != ".png" && ext != ".exr"), entry.path().string());
  }
  const io::Json only_record = io::read_json(only + "/render.json");
  CHECK(only_record["formats"] == "none");
  CHECK(only_record["video"]["crf"] == 10);
  const io::Json transforms = io::read_json(only + "/transforms.json");
  CHECK(transforms["frames"][0]["file_path"] == "frame_0000");  // the frame's name; no image file was written
  const io::VideoFrames only_decoded = io::read_video_frames(only + "/orbit.mp4");
  REQUIRE(only_decoded.frames.size() == 4);
  CHECK(only_decoded.fps == doctest::Approx(30.0).epsilon(1e-9));  // the default
  for (int k = 0; k < 4; ++k) {
    const io::PngImage png = io::read_png(out + "/" + frame_stem(k) + ".png");
    CHECK(psnr(only_decoded.frames[k], rgb_of(png), 48, 32) >= 35.0);
  }
  fs::remove_all(out);
  fs::remove_all(only);
}
