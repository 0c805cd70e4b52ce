// A run folder as the viewer shows it.
#include "view/run_state.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "train/checkpoint.hpp"

namespace mipnerf::view {
namespace fs = std::filesystem;
namespace {

constexpr std::uintmax_t kMaxLogBytes = 32u << 20;  // a log this large is not a run's (1e5 steps ≈ 8 MB)
constexpr size_t kMaxImages = 400;                  // images listed, per run

std::vector<std::string> split_commas(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream in(line);
  std::string cell;
  while (std::getline(in, cell, ',')) cells.push_back(cell);
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

nlohmann::json number_or_null(const std::string& cell) {
  if (cell.empty()) return nullptr;
  char* end = nullptr;
  const double v = std::strtod(cell.c_str(), &end);
  if (end != cell.c_str() + cell.size() || !std::isfinite(v)) return nullptr;
  return v;
}

// The images of one folder: X.png with X_gt.png / X_error.png beside it when they exist.
void add_images(const fs::path& run, const fs::path& folder, nlohmann::json& images) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) return;
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (entry.path().extension() != ".png") continue;
    const std::string stem = entry.path().stem().string();
    if (stem.size() > 3 && stem.compare(stem.size() - 3, 3, "_gt") == 0) continue;
    if (stem.size() > 6 && stem.compare(stem.size() - 6, 6, "_error") == 0) continue;
    names.push_back(stem);
  }
  std::sort(names.begin(), names.end());
  const std::string rel = fs::relative(folder, run, ec).generic_string();
  for (const auto& stem : names) {
    if (images.size() >= kMaxImages) return;
    auto beside = [&](const std::string& suffix) {
      return fs::exists(folder / (stem + suffix + ".png"), ec) ? rel + "/" + stem + suffix + ".png" : std::string();
    };
    images.push_back({{"folder", rel}, {"name", stem}, {"render", rel + "/" + stem + ".png"}, {"gt", beside("_gt")},
                      {"error", beside("_error")}});
  }
}

}  // namespace

nlohmann::json read_csv_log(const std::string& path, size_t max_rows) {
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  if (ec || size > kMaxLogBytes) return nullptr;
  std::ifstream in(path);
  std::string line;
  if (!std::getline(in, line)) return nullptr;
  const std::vector<std::string> columns = split_commas(line);
  std::vector<nlohmann::json> rows;
  while (std::getline(in, line)) {
    if (in.eof()) break;  // no newline yet: a row being written
    const auto cells = split_commas(line);
    if (cells.size() != columns.size()) continue;
    nlohmann::json row = nlohmann::json::array();
    for (const auto& c : cells) row.push_back(number_or_null(c));
    rows.push_back(std::move(row));
  }
  nlohmann::json kept = nlohmann::json::array();
  const size_t stride = max_rows == 0 ? 1 : (rows.size() + max_rows - 1) / std::max<size_t>(max_rows, 1);
  for (size_t i = 0; i < rows.size(); ++i) {
    if (i % std::max<size_t>(stride, 1) == 0 || i + 1 == rows.size()) kept.push_back(rows[i]);
  }
  return {{"columns", columns}, {"rows", kept}};
}

nlohmann::json run_state(const std::string& run_folder) {
  const fs::path run(run_folder);
  nlohmann::json state;
  state["name"] = run.filename().string();
  std::ifstream config_file(run / "config.json");
  nlohmann::json config = nlohmann::json::parse(config_file, nullptr, false);
  state["config"] = config.is_discarded() ? nlohmann::json(nullptr) : config;
  state["train_log"] = read_csv_log((run / "train_log.csv").string());
  state["val_log"] = read_csv_log((run / "val_log.csv").string());
  nlohmann::json steps = nlohmann::json::array();
  std::error_code ec;
  if (fs::is_directory(run / "checkpoints", ec)) {
    for (const auto& [step, path] : train::list_checkpoints((run / "checkpoints").string())) steps.push_back(step);
  }
  state["checkpoints"] = steps;
  nlohmann::json images = nlohmann::json::array();
  add_images(run, run / "val", images);
  for (const auto& entry : fs::directory_iterator(run, ec)) {
    if (entry.is_directory(ec) && fs::is_directory(entry.path() / "images", ec)) add_images(run, entry.path() / "images", images);
  }
  state["images"] = images;
  return state;
}

}  // namespace mipnerf::view
