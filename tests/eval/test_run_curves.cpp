// eval::val_psnr_curve: a run folder's val_log.csv as a plot series, labelled with the folder and the variant its
// config.json records; a folder without scores, a foreign header or a malformed row is one line naming the file.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "eval/run_curves.hpp"
#include "support/temp_scene.hpp"

using namespace mipnerf;
namespace fs = std::filesystem;

namespace {

fs::path run_with_log(const std::string& name, const std::string& log, const std::string& config = "") {
  const auto dir = test::fresh_temp_dir("curves-" + name) / name;
  fs::create_directories(dir);
  std::ofstream(dir / "val_log.csv") << log;
  if (!config.empty()) std::ofstream(dir / "config.json") << config;
  return dir;
}

const char* const kHeader = "step,train_seconds,val_psnr,val_ssim,val_images,val_seconds\n";

}  // namespace

TEST_CASE("run curves: val PSNR against training seconds or steps, labelled with the folder and its variant") {
  const auto dir =
      run_with_log("quick-lego", std::string(kHeader) + "100,12.5,18.25,0.6,4,2.1\n200,25,20.5,0.7,4,2.0\n",
                   R"({"variant": "mipnerf", "variant_bundle": "mipnerf-concat-pe"})");
  const auto by_seconds = eval::val_psnr_curve(dir.string(), eval::CurveX::train_seconds);
  CHECK(by_seconds.label == "quick-lego (mipnerf-concat-pe)");
  CHECK(by_seconds.x == std::vector<double>{12.5, 25.0});
  CHECK(by_seconds.y == std::vector<double>{18.25, 20.5});
  CHECK(eval::val_psnr_curve(dir.string(), eval::CurveX::steps).x == std::vector<double>{100, 200});
  // A folder whose name says its variant is not labelled twice; without config.json the folder's name alone.
  const auto same =
      run_with_log("quick-nerf", std::string(kHeader) + "1,1,10,0.1,1,1\n", R"({"variant_bundle": "nerf"})");
  CHECK(eval::val_psnr_curve(same.string(), eval::CurveX::steps).label == "quick-nerf");
  const auto bare = run_with_log("bare", std::string(kHeader) + "1,1,10,0.1,1,1\n");
  CHECK(eval::val_psnr_curve(bare.string() + "/", eval::CurveX::steps).label == "bare");
  const auto plot = eval::val_psnr_plot({dir.string(), bare.string()}, eval::CurveX::train_seconds, "t");
  CHECK(plot.series.size() == 2);
  CHECK(plot.x_label == "training seconds (val scoring excluded)");
}

TEST_CASE("run curves: no val_log.csv, another header, a malformed row or no rows are one line naming the file") {
  const auto empty = test::fresh_temp_dir("curves-none");
  CHECK_THROWS_WITH_AS(eval::val_psnr_curve(empty.string(), eval::CurveX::steps),
                       doctest::Contains("val_log.csv: no val scores in this run folder; train with --set val_every=N"),
                       Error);
  const auto foreign = run_with_log("foreign", "step,wall_seconds,loss\n1,2,3\n");
  CHECK_THROWS_WITH_AS(eval::val_psnr_curve(foreign.string(), eval::CurveX::steps),
                       doctest::Contains("val_log.csv: line 1 is not the header"), Error);
  const auto broken = run_with_log("broken", std::string(kHeader) + "1,1,10,0.1,1,1\n2;2;11\n");
  CHECK_THROWS_WITH_AS(eval::val_psnr_curve(broken.string(), eval::CurveX::steps),
                       doctest::Contains("val_log.csv: line 3 is not 'step,train_seconds,val_psnr,...'"), Error);
  const auto nothing = run_with_log("nothing", kHeader);
  CHECK_THROWS_WITH_AS(eval::val_psnr_curve(nothing.string(), eval::CurveX::steps),
                       doctest::Contains("no val scores yet"), Error);
}
