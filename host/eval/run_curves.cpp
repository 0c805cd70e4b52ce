// val_log.csv → plot series.
#include "eval/run_curves.hpp"

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/error.hpp"
#include "io/file.hpp"
#include "train/trainer.hpp"

namespace mipnerf::eval {
namespace fs = std::filesystem;
namespace {

// "name (variant)" from the folder's name and the variant_bundle config.json records (when it does and the name
// does not already say it).
std::string run_label(const fs::path& dir) {
  std::string name = dir.lexically_normal().filename().string();
  if (name.empty() || name == ".") name = fs::absolute(dir).lexically_normal().parent_path().filename().string();
  std::error_code ec;
  const fs::path config = dir / "config.json";
  if (!fs::exists(config, ec)) return name;
  const auto j = nlohmann::json::parse(io::read_file_text(config.string()), nullptr, false);
  if (j.is_object() && j.contains("variant_bundle") && j["variant_bundle"].is_string()) {
    const std::string variant = j["variant_bundle"].get<std::string>();
    if (name.find(variant) == std::string::npos) return name + " (" + variant + ")";  // said once is enough
  }
  return name;
}

}  // namespace

io::PlotSeries val_psnr_curve(const std::string& run_dir, CurveX x) {
  const fs::path csv = fs::path(run_dir) / "val_log.csv";
  std::error_code ec;
  if (!fs::is_regular_file(csv, ec)) {
    throw Error(csv.string() +
                ": no val scores in this run folder; train with --set val_every=N (steps between "
                "val scores) to record them");
  }
  std::istringstream lines(io::read_file_text(csv.string()));
  std::string line;
  if (!std::getline(lines, line) || line != train::kValLogColumns) {
    throw Error(csv.string() + ": line 1 is not the header '" + std::string(train::kValLogColumns) + "'");
  }
  io::PlotSeries series;
  series.label = run_label(fs::path(run_dir));
  for (int number = 2; std::getline(lines, line); ++number) {
    if (line.empty()) continue;
    std::istringstream fields(line);
    double step = 0, seconds = 0, psnr = 0;
    char comma1 = 0, comma2 = 0, comma3 = 0;
    fields >> step >> comma1 >> seconds >> comma2 >> psnr >> comma3;
    if (fields.fail() || comma1 != ',' || comma2 != ',' || comma3 != ',' || !std::isfinite(psnr) ||
        !std::isfinite(seconds)) {
      throw Error(csv.string() + ": line " + std::to_string(number) + " is not 'step,train_seconds,val_psnr,...'");
    }
    series.x.push_back(x == CurveX::steps ? step : seconds);
    series.y.push_back(psnr);
  }
  if (series.x.empty()) {
    throw Error(csv.string() + ": no val scores yet (the run stopped before its first val_every steps)");
  }
  return series;
}

io::LinePlot val_psnr_plot(const std::vector<std::string>& run_dirs, CurveX x, const std::string& title) {
  io::LinePlot plot;
  plot.title = title;
  plot.x_label = x == CurveX::steps ? "training steps" : "training seconds (val scoring excluded)";
  plot.y_label = "val PSNR (dB)";
  for (const auto& dir : run_dirs) plot.series.push_back(val_psnr_curve(dir, x));
  return plot;
}

}  // namespace mipnerf::eval
