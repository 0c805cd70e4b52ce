// Evaluation (host/eval/evaluate, report) and the real `mipnerf-cl eval` and `mipnerf-cl render`: the numbers in
// metrics.json are those eval::psnr and eval::ssim give on the images it wrote, per image and per scale, and the
// files render writes are the frames asked for.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>

#include "core/error.hpp"
#include "data/paths/camera_path.hpp"
#include "data/dataset.hpp"
#include "eval/evaluate.hpp"
#include "eval/image_output.hpp"
#include "eval/metrics.hpp"
#include "eval/render_setup.hpp"
#include "eval/report.hpp"
#include "io/color.hpp"
#include "io/exr.hpp"
#include "io/file.hpp"
#include "io/json.hpp"
#include "io/png.hpp"
#include "render_fixtures.hpp"

using namespace mipnerf;
namespace fs = std::filesystem;
using test::trained_model;

namespace {

eval::ImageView view(const float* pixels, uint32_t width, uint32_t height) { return {pixels, height, width, 3}; }

// The run folder (parent of checkpoints/) of the fixture model.
std::string run_folder() { return fs::path(test::trained_checkpoint()).parent_path().parent_path().string(); }

}  // namespace

TEST_CASE("render: evaluation scores every scale, and its report holds exactly those numbers") {
  // The test split with 3 scales built on the fly: 16, 8 and 4 pixels; SSIM exists only at 16 (window 11).
  data::LoadOptions load;
  load.scales = 3;
  load.splits = {"test"};
  const auto dataset = data::load_dataset(test::render_scene(), load);
  const auto& split = dataset.split("test");
  REQUIRE(split.num_images() == 6);
  auto renderer = test::trained_renderer(split.cameras, eval::RenderSettings{512, 1, 0});
  size_t last_rays = 0, total = 0;
  eval::EvaluateOptions options;
  options.ray_progress = [&](size_t done, size_t all) {
    CHECK(done > last_rays);
    last_rays = done;
    total = all;
  };
  const auto scores = eval::evaluate_split(renderer, split, options);
  CHECK(total == 2u * (256 + 64 + 16));
  CHECK(last_rays == total);
  REQUIRE(scores.images.size() == 6);
  REQUIRE(scores.scales.size() == 3);
  // Each image's score is eval::psnr / eval::ssim of an independent render of it.
  auto again = test::trained_renderer(split.cameras, eval::RenderSettings{512, 1, 0});
  std::map<uint32_t, std::vector<double>> psnr_by_scale;
  for (const auto& score : scores.images) {
    const auto image = again.render(score.index);
    const auto& camera = split.cameras[score.index];
    const double psnr = eval::psnr(view(image.rgb.data(), camera.width_px, camera.height_px),
                                   view(split.image_rgb(score.index), camera.width_px, camera.height_px));
    CHECK(score.psnr == psnr);  // the same deterministic render, the same double arithmetic
    CHECK(score.scale_level == split.scale_levels[score.index]);
    CHECK(score.has_ssim == (camera.width_px >= 11));
    if (score.has_ssim) {
      CHECK(score.ssim == eval::ssim(view(image.rgb.data(), camera.width_px, camera.height_px),
                                     view(split.image_rgb(score.index), camera.width_px, camera.height_px)));
    }
    psnr_by_scale[score.scale_level].push_back(psnr);
  }
  for (const auto& s : scores.scales) {
    INFO("scale " << s.scale_level);
    CHECK(s.images == 2);
    CHECK(s.width == 16u >> s.scale_level);
    const auto& values = psnr_by_scale[s.scale_level];
    CHECK(s.mean_psnr == doctest::Approx((values[0] + values[1]) / 2).epsilon(1e-15));  // mean of PSNRs, not of MSEs
    CHECK(s.ssim_images == (s.scale_level == 0 ? 2u : 0u));
    CHECK(std::isnan(s.mean_ssim) == (s.scale_level != 0));
    CHECK(s.seconds_per_megapixel() > 0.0);
  }
  CHECK(scores.ssim_images == 2);
  CHECK(scores.mean_ssim == doctest::Approx(scores.scales[0].mean_ssim).epsilon(1e-15));  // only scale 0 has SSIMs

  eval::EvalRecord record;
  record.checkpoint = test::trained_checkpoint();
  record.step = 10;
  record.split = "test";
  record.image_stems = eval::split_image_stems(split);
  record.date = eval::utc_timestamp();
  record.device = eval::device_record(test::test_context().device_info());
  record.supersample = 1;
  record.chunk_rays = 512;
  record.image_folder = "images";
  // Through text and back, as a reader of metrics.json sees it.
  const io::Json j = io::parse_json(eval::metrics_json(scores, record).dump(2), "metrics.json");
  CHECK(j["step"] == 10);
  CHECK(j["device"]["name"] == test::test_context().device_info().name);
  CHECK(j["metrics"]["ssim"].get<std::string>().find("11x11 Gaussian window (sigma 1.5") != std::string::npos);
  CHECK(j["metrics"]["psnr"].get<std::string>().find("-10*log10(MSE)") != std::string::npos);
  CHECK(j["date"].get<std::string>().size() == 20);
  REQUIRE(j["images"].size() == 6);
  for (size_t k = 0; k < 6; ++k) {
    CHECK(j["images"][k]["psnr"].get<double>() == scores.images[k].psnr);  // 17 significant digits: exact
    CHECK(j["images"][k]["ssim"].is_null() == !scores.images[k].has_ssim);
  }
  CHECK(j["images"][1]["render"] == "images/000_scale1.png");  // view 0, ×2
  CHECK(j["images"][3]["error"] == "images/001_scale0_error.png");
  CHECK(j["images"][5]["ground_truth"] == "images/001_scale2_gt.png");
  REQUIRE(j["scales"].size() == 3);
  CHECK(j["scales"][2]["downsampling"] == 4);
  CHECK(j["scales"][1]["ssim"].is_null());
  CHECK(j["scales"][0]["psnr"].get<double>() == scores.scales[0].mean_psnr);
  CHECK(j["mean"]["psnr"].get<double>() == scores.mean_psnr);
  CHECK(j["render"]["seconds_per_megapixel"].get<double>() == scores.seconds_per_megapixel());
  const std::string md = eval::metrics_markdown(scores, record);
  CHECK(md.find("| scale | resolution | images | PSNR (dB) | SSIM | render s/MP |") != std::string::npos);
  CHECK(md.find("| 1/4 | 4x4 | 2 | ") != std::string::npos);
  char row[96];
  std::snprintf(row, sizeof(row), "| 1 (full) | 16x16 | 2 | %.2f | %.4f |", scores.scales[0].mean_psnr,
                scores.scales[0].mean_ssim);
  CHECK(md.find(row) != std::string::npos);
}

TEST_CASE("render: eval and render find the data a checkpoint records, or say to pass --data") {
  train::TrainedModel recorded;
  recorded.data_path = test::render_scene();
  CHECK(eval::resolve_data_path("", recorded, "ckpt.mnck") == test::render_scene());
  CHECK(eval::resolve_data_path("elsewhere", recorded, "ckpt.mnck") == "elsewhere");
  train::TrainedModel moved;
  moved.data_path = (test::render_temp("moved") / "scene").string();
  const std::string gone = "ckpt.mnck was trained on " + moved.data_path + ", which no longer exists: pass --data";
  CHECK_THROWS_WITH_AS(eval::resolve_data_path("", moved, "ckpt.mnck"), doctest::Contains(gone.c_str()), Error);
  CHECK_THROWS_WITH_AS(eval::resolve_data_path("", train::TrainedModel{}, "old.mnck"),
                       doctest::Contains("old.mnck does not record the data it was trained on: pass --data DIR"),
                       Error);
  // Load options follow training: a multiscale run builds 4 scales on the fly, except from data already multiscale.
  train::TrainConfig config;
  config.multiscale = true;
  config.background = Background::black;
  config.near = 1.5;
  const auto blender = train::load_options(config, test::render_scene(), {"test"});
  CHECK(blender.scales == 4);
  CHECK(blender.background == Background::black);
  CHECK(blender.near == 1.5);
  CHECK(!blender.far.has_value());
  CHECK(train::load_options(config, test::render_scene() + "/multiscale", {"test"}).scales == 1);
  CHECK(train::load_options(config, test::render_scene(), {"test"}, 2).scales == 2);
  CHECK(eval::run_folder_of("/runs/a/checkpoints/ckpt_000000010.mnck") == "/runs/a");
  CHECK(eval::run_folder_of("/somewhere/model.mnck") == "/somewhere");
  CHECK(eval::run_folder_of("runs/b/checkpoints/ckpt_000000010.mnck") == "runs/b");
  CHECK(eval::run_folder_of("model.mnck") == ".");
}

TEST_CASE("render: mipnerf-cl eval writes metrics that agree with the images it wrote") {
  const std::string out = test::fresh_temp_dir("render-cli-eval").string();
  // No --data: the checkpoint's recorded scene; --scales 2 builds its ×2 copies on the fly.
  const auto result = test::run_cli("eval --checkpoint " + run_folder() + " --scales 2 --exr --out " + out);
  INFO(result.err);
  REQUIRE(result.exit_code == 0);
  CHECK(result.out.find("| 1/2 | 8x8 | 2 |") != std::string::npos);
  CHECK(result.out.find("mean PSNR") != std::string::npos);
  const io::Json metrics = io::read_json((fs::path(out) / "metrics.json").string());
  CHECK(metrics["step"] == 10);
  CHECK(metrics["split"] == "test");
  CHECK(metrics["data"] == fs::absolute(test::render_scene()).lexically_normal().string());
  CHECK(metrics["device"]["name"] == test::test_context().device_info().name);
  CHECK(metrics["device"]["driver_version"] == test::test_context().device_info().driver_version);
  CHECK(metrics["render"]["seconds_per_megapixel"].get<double>() > 0.0);
  data::LoadOptions load;
  load.scales = 2;
  load.splits = {"test"};
  const auto dataset = data::load_dataset(test::render_scene(), load);
  const auto& split = dataset.split("test");
  REQUIRE(metrics["images"].size() == split.num_images());
  const auto stems = eval::split_image_stems(split);
  std::map<uint32_t, std::pair<double, int>> psnr_sums;
  for (const auto& entry : metrics["images"]) {
    const size_t index = entry["index"].get<size_t>();
    INFO("image " << index);
    const auto& camera = split.cameras[index];
    const std::string stem = (fs::path(out) / "images" / stems[index]).string();
    CHECK(entry["render"].get<std::string>() == "images/" + fs::path(stem).filename().string() + ".png");
    // The float render, back from the EXR's linear RGB to the network's encoded values.
    const io::ExrImage exr = io::read_exr(stem + ".exr");
    std::vector<float> rendered(exr.rgb.size());
    io::linear_to_srgb(exr.rgb.data(), rendered.data(), rendered.size());
    const auto rendered_view = view(rendered.data(), camera.width_px, camera.height_px);
    const auto truth_view = view(split.image_rgb(index), camera.width_px, camera.height_px);
    // sRGB → linear → sRGB in float32 moves each value by ~1e-7, the MSE (~1e-2) relatively by ~1e-5: PSNR
    // agrees to far better than 1e-3 dB, SSIM to far better than 1e-5.
    CHECK(std::abs(entry["psnr"].get<double>() - eval::psnr(rendered_view, truth_view)) < 1e-3);
    if (camera.width_px >= 11) {
      CHECK(entry["ssim"].get<double>() == doctest::Approx(eval::ssim(rendered_view, truth_view)).epsilon(1e-5));
    } else {
      CHECK(entry["ssim"].is_null());
    }
    psnr_sums[split.scale_levels[index]].first += entry["psnr"].get<double>();
    ++psnr_sums[split.scale_levels[index]].second;
    // The PNGs: the render and the ground truth as 8-bit codes, the error as mean |difference| × 4.
    const io::PngImage png = io::read_png(stem + ".png"), gt = io::read_png(stem + "_gt.png"),
                       error = io::read_png(stem + "_error.png");
    for (size_t p = 0; p < static_cast<size_t>(camera.width_px) * camera.height_px; ++p) {
      double difference = 0.0;
      for (int c = 0; c < 3; ++c) {
        // Within half a code plus the EXR round trip.
        REQUIRE(std::abs(png.rgba[4 * p + c] - std::clamp(rendered[3 * p + c], 0.0f, 1.0f)) <= 0.5 / 255 + 1e-6);
        REQUIRE(std::abs(gt.rgba[4 * p + c] - split.image_rgb(index)[3 * p + c]) <= 0.5 / 255 + 1e-6);
        difference += std::abs(rendered[3 * p + c] - split.image_rgb(index)[3 * p + c]) / 3.0;
      }
      REQUIRE(std::abs(error.rgba[4 * p] - std::min(1.0, 4.0 * difference)) <= 0.5 / 255 + 1e-5);
    }
    // The depth and accumulation channels are there, finite.
    REQUIRE(exr.depth.size() == exr.acc.size());
    for (float d : exr.depth) REQUIRE(std::isfinite(d));
  }
  // Per-scale means are the means of the per-image values.
  REQUIRE(metrics["scales"].size() == 2);
  for (const auto& s : metrics["scales"]) {
    const auto& [sum, count] = psnr_sums[s["scale_level"].get<uint32_t>()];
    CHECK(count == 2);
    CHECK(s["psnr"].get<double>() == doctest::Approx(sum / count).epsilon(1e-14));
  }
  CHECK(metrics["scales"][1]["ssim"].is_null());  // 8×8 images are smaller than the 11×11 window
  const std::string md = io::read_file_text((fs::path(out) / "metrics.md").string());
  CHECK(md.find("| 1/2 | 8x8 | 2 |") != std::string::npos);
  fs::remove_all(out);
}

TEST_CASE(
    "render: mipnerf-cl render writes split, orbit and path frames, and a render's transforms.json renders it again") {
  const std::string split_out = test::fresh_temp_dir("render-cli-split").string();
  auto result = test::run_cli("render --checkpoint " + test::trained_checkpoint() + " --split test --scale 0.5 --out " +
                              split_out);
  INFO(result.err);
  REQUIRE(result.exit_code == 0);
  CHECK(result.out.find("rendered 2 frames of the test split") != std::string::npos);
  for (const char* name : {"000.png", "001.png", "transforms.json", "render.json"}) {
    CHECK(fs::exists(fs::path(split_out) / name));
  }
  // Each frame is the library's render of the split camera at half size (the same device, chunking and kernels).
  const auto dataset = data::load_dataset(test::render_scene(), {});
  const auto camera = data::resize_camera(dataset.split("test").cameras[1], {0.5, 0, 0});
  auto renderer = test::trained_renderer(
      {camera}, eval::RenderSettings{static_cast<size_t>(trained_model().config.render_chunk_rays), 1, 0});
  const auto expected = renderer.render(0);
  const io::PngImage frame = io::read_png((fs::path(split_out) / "001.png").string());
  REQUIRE(frame.width == 8);
  for (size_t p = 0; p < 64; ++p) {
    for (int c = 0; c < 3; ++c) {
      REQUIRE(frame.rgba[4 * p + c] * 255.0 ==
              doctest::Approx(std::round(std::clamp(expected.rgb[3 * p + c], 0.0f, 1.0f) * 255.0)).epsilon(1e-6));
    }
  }

  // An orbit at another size, supersampled, in both formats.
  const std::string orbit_out = test::fresh_temp_dir("render-cli-orbit").string();
  result = test::run_cli("render --checkpoint " + run_folder() +
                         " --path orbit --frames 3 --elevation 40 --size 12x8 "
                         "--supersample 2 --format both --out " +
                         orbit_out);
  INFO(result.err);
  REQUIRE(result.exit_code == 0);
  CHECK(result.out.find("rendered 3 frames of an orbit (12x8, 2 rays per pixel)") != std::string::npos);
  for (int k = 0; k < 3; ++k) {
    const std::string stem = (fs::path(orbit_out) / ("frame_000" + std::to_string(k))).string();
    CHECK(io::read_png(stem + ".png").width == 12);
    const io::ExrImage exr = io::read_exr(stem + ".exr");
    CHECK(exr.height == 8);
    CHECK(exr.depth.size() == 96);
    CHECK(exr.acc.size() == 96);
  }
  const io::Json record = io::read_json((fs::path(orbit_out) / "render.json").string());
  CHECK(record["rays_per_pixel"] == 2);
  CHECK(record["source"]["fitted_to_training_cameras"] == true);
  CHECK(record["source"]["radius"].get<double>() == doctest::Approx(4.0).epsilon(1e-9));  // the scene's cameras
  // The orbit's cameras, fitted to the training cameras: 40° elevation about the look-at centre, the training size's
  // field of view at 12 pixels wide.
  const auto cameras = data::read_camera_path((fs::path(orbit_out) / "transforms.json").string(), {});
  REQUIRE(cameras.size() == 3);
  const auto train_camera = data::load_dataset(test::render_scene(), {}).split("train").cameras[0];
  CHECK(cameras[0].focal_x_px == doctest::Approx(train_camera.focal_x_px * 12.0 / 16.0).epsilon(1e-12));
  CHECK(data::camera_center(cameras[1])[2] == doctest::Approx(4.0 * std::sin(40.0 * M_PI / 180.0)).epsilon(1e-9));

  // Its transforms.json as a camera path renders the same frames again, bit for bit (the same rays and jitter).
  const std::string again_out = test::fresh_temp_dir("render-cli-again").string();
  result = test::run_cli("render --checkpoint " + run_folder() + " --path " + orbit_out +
                         "/transforms.json --supersample 2 --format exr --out " + again_out);
  INFO(result.err);
  REQUIRE(result.exit_code == 0);
  for (int k = 0; k < 3; ++k) {
    const std::string name = "frame_000" + std::to_string(k) + ".exr";
    const io::ExrImage a = io::read_exr((fs::path(orbit_out) / name).string());
    const io::ExrImage b = io::read_exr((fs::path(again_out) / name).string());
    CHECK(a.rgb == b.rgb);
    CHECK(a.depth == b.depth);
    CHECK(a.acc == b.acc);
  }
  fs::remove_all(split_out);
  fs::remove_all(orbit_out);
  fs::remove_all(again_out);
}
