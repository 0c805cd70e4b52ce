// metrics.json and metrics.md of an evaluation, summary.json of a training run, render.json of a render.
#include "eval/report.hpp"

#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <sstream>

#include "eval/image_output.hpp"
#include "io/atomic_file.hpp"

namespace mipnerf::eval {

const char* const kPsnrDefinition =
    "per image: -10*log10(MSE), the MSE over every pixel and RGB channel of the rendered against the ground-truth "
    "image (values in [0, 1], the PNGs' sRGB-encoded values composited onto the background); means average the "
    "per-image PSNRs (google/mipnerf eval.py)";
const char* const kSsimDefinition =
    "per image: SSIM with an 11x11 Gaussian window (sigma 1.5, separable, 'valid' filtering), k1 0.01, k2 0.03, "
    "data range 1, the official variance/covariance clamps, averaged over pixels and RGB channels "
    "(google/mipnerf compute_ssim); images smaller than the window have none (null) and means leave them out";

namespace {

using Ordered = nlohmann::ordered_json;

Ordered number_or_null(double v) { return std::isfinite(v) ? Ordered(v) : Ordered(nullptr); }

std::string fixed(double v, int decimals) {
  if (!std::isfinite(v)) return "–";
  char text[32];
  std::snprintf(text, sizeof(text), "%.*f", decimals, v);
  return text;
}

std::string scale_name(uint32_t level) {
  return level == 0 ? std::string("1 (full)") : "1/" + std::to_string(1u << level);
}

std::string formats_name(const OutputFormats& formats) {
  return formats.png && formats.exr ? "png, exr" : formats.png ? "png" : "exr";
}

void write_json_atomically(const std::string& path, const Ordered& j) {
  io::write_bytes_atomically(path, j.dump(2) + "\n");
}

Ordered val_summary(const SplitScores& val) {
  Ordered j;
  j["views"] = val.images.size();
  j["mean_psnr"] = val.mean_psnr;
  j["mean_ssim"] = val.mean_ssim;
  j["render_seconds_per_megapixel"] = val.seconds_per_megapixel();
  for (const auto& s : val.scales) {
    j["scales"].push_back(
        {{"scale_level", s.scale_level}, {"images", s.images}, {"mean_psnr", s.mean_psnr}, {"mean_ssim", s.mean_ssim}});
  }
  return j;
}

}  // namespace

Ordered metrics_json(const SplitScores& scores, const EvalRecord& r) {
  Ordered j = Ordered::object();
  j["checkpoint"] = r.checkpoint;
  j["step"] = r.step;
  j["train_seconds"] = r.train_seconds;
  j["trained_on"] = r.trained_on;
  j["data"] = r.data;
  j["split"] = r.split;
  j["date"] = r.date;
  j["device"] = r.device;
  j["model"] = r.model;
  j["metrics"] = {{"psnr", kPsnrDefinition}, {"ssim", kSsimDefinition}};
  j["render"] = {
      {"rays_per_pixel", r.supersample},
      {"supersampling", r.supersample > 1 ? "jittered: rays through uniformly random points of the pixel, averaged"
                                          : "none: one ray through the pixel's centre offset"},
      {"chunk_rays", r.chunk_rays},
      {"warm_up_seconds", r.warm_up_seconds},
      {"render_seconds", scores.render_seconds},
      {"megapixels", scores.megapixels},
      {"seconds_per_megapixel", scores.seconds_per_megapixel()}};
  j["mean"] = {{"images", scores.images.size()},
               {"psnr", number_or_null(scores.mean_psnr)},
               {"ssim", number_or_null(scores.mean_ssim)},
               {"ssim_images", scores.ssim_images}};
  Ordered scales = Ordered::array();
  for (const auto& s : scores.scales) {
    scales.push_back({{"scale_level", s.scale_level},
                      {"downsampling", 1u << s.scale_level},
                      {"width", s.width},
                      {"height", s.height},
                      {"images", s.images},
                      {"psnr", number_or_null(s.mean_psnr)},
                      {"ssim", number_or_null(s.mean_ssim)},
                      {"ssim_images", s.ssim_images},
                      {"render_seconds", s.render_seconds},
                      {"megapixels", s.megapixels},
                      {"seconds_per_megapixel", s.seconds_per_megapixel()}});
  }
  j["scales"] = std::move(scales);
  Ordered images = Ordered::array();
  for (const auto& image : scores.images) {
    Ordered e = {{"index", image.index},
                 {"file", image.file},
                 {"scale_level", image.scale_level},
                 {"width", image.width},
                 {"height", image.height},
                 {"psnr", number_or_null(image.psnr)},
                 {"ssim", image.has_ssim ? number_or_null(image.ssim) : Ordered(nullptr)},
                 {"render_seconds", image.seconds}};
    if (!r.image_folder.empty() && image.index < r.image_stems.size()) {
      const std::string stem = r.image_folder + "/" + r.image_stems[image.index];
      e["render"] = stem + ".png";
      e["ground_truth"] = stem + "_gt.png";
      e["error"] = stem + "_error.png";
    }
    images.push_back(std::move(e));
  }
  j["images"] = std::move(images);
  return j;
}

std::string scale_table_markdown(const SplitScores& scores) {
  std::ostringstream t;
  t << "| scale | resolution | images | PSNR (dB) | SSIM | render s/MP |\n";
  t << "|---|---|---:|---:|---:|---:|\n";
  for (const auto& s : scores.scales) {
    t << "| " << scale_name(s.scale_level) << " | " << s.width << "x" << s.height << " | " << s.images << " | "
      << fixed(s.mean_psnr, 2) << " | " << fixed(s.mean_ssim, 4) << " | " << fixed(s.seconds_per_megapixel(), 2)
      << " |\n";
  }
  t << "| **mean** | | " << scores.images.size() << " | " << fixed(scores.mean_psnr, 2) << " | "
    << fixed(scores.mean_ssim, 4) << " | " << fixed(scores.seconds_per_megapixel(), 2) << " |\n";
  return t.str();
}

std::string metrics_markdown(const SplitScores& scores, const EvalRecord& r) {
  std::ostringstream md;
  md << "# Evaluation: step " << r.step << " of `" << r.checkpoint << "`\n\n";
  md << "The " << r.split << " split of `" << r.data << "` (" << scores.images.size() << " images), rendered on "
     << r.device.value("name", std::string("?")) << " (" << r.device.value("platform", std::string("?")) << ", driver "
     << r.device.value("driver_version", std::string("?")) << ") on " << r.date << ", " << r.supersample
     << (r.supersample == 1 ? " ray" : " jittered rays") << " per pixel, chunks of " << r.chunk_rays
     << " rays. Render seconds per megapixel exclude the warm-up (" << fixed(r.warm_up_seconds, 2) << " s).\n\n";
  md << scale_table_markdown(scores) << "\n";
  md << "- **PSNR**: " << kPsnrDefinition << ".\n";
  md << "- **SSIM**: " << kSsimDefinition << ".\n\n";
  md << "## Per image\n\n";
  md << "| image | scale | resolution | PSNR (dB) | SSIM | render s | ground truth |\n";
  md << "|---:|---|---|---:|---:|---:|---|\n";
  for (const auto& image : scores.images) {
    const bool named = image.index < r.image_stems.size();
    md << "| " << (named ? r.image_stems[image.index] : std::to_string(image.index)) << " | "
       << scale_name(image.scale_level) << " | " << image.width << "x" << image.height << " | " << fixed(image.psnr, 2)
       << " | " << (image.has_ssim ? fixed(image.ssim, 4) : std::string("–")) << " | " << fixed(image.seconds, 3)
       << " | " << image.file << " |\n";
  }
  return md.str();
}

std::string utc_timestamp() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

TrainRecord train_record(const train::Trainer& trainer, const std::string& device) {
  TrainRecord r;
  r.device = device;
  r.parameters = trainer.parameter_count();
  r.chunk_rays = trainer.memory().chunk_rays;
  r.planned_device_bytes = trainer.memory().total();
  return r;
}

Ordered summary_json(const TrainRecord& record, const train::TrainResult& result, const SplitScores* val) {
  Ordered j;
  j["device"] = record.device;
  j["steps"] = result.last_step;
  j["interrupted"] = result.interrupted;
  j["train_seconds"] = result.train_seconds;
  j["skipped_steps"] = result.skipped_steps;
  j["parameters"] = record.parameters;
  j["chunk_rays"] = record.chunk_rays;
  j["planned_device_bytes"] = record.planned_device_bytes;
  j["checkpoint"] = result.checkpoint;
  if (val) j["val"] = val_summary(*val);
  return j;
}

std::string summary_path(const std::string& out_dir) {
  return (std::filesystem::path(out_dir) / "summary.json").string();
}

std::optional<io::Json> read_summary(const std::string& out_dir) {
  const std::string path = summary_path(out_dir);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return std::nullopt;
  try {
    return io::read_json(path);
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

std::string write_summary(const std::string& out_dir, const TrainRecord& record, const train::TrainResult& result,
                          const SplitScores* val) {
  const std::string path = summary_path(out_dir);
  write_json_atomically(path, summary_json(record, result, val));
  return path;
}

Ordered render_json(const RenderRecord& r) {
  Ordered j;
  j["checkpoint"] = r.checkpoint;
  j["step"] = r.step;
  j["source"] = r.source;
  j["date"] = r.date;
  j["device"] = r.device;
  j["frames"] = r.frames;
  j["formats"] = formats_name(r.formats);
  j["rays_per_pixel"] = r.rays_per_pixel;
  j["chunk_rays"] = r.chunk_rays;
  j["warm_up_seconds"] = r.warm_up_seconds;
  j["render_seconds"] = r.render_seconds;
  j["megapixels"] = r.megapixels;
  j["seconds_per_megapixel"] = r.megapixels > 0 ? r.render_seconds / r.megapixels : 0.0;
  return j;
}

void write_render_record(const std::string& folder, const RenderRecord& record) {
  write_json_atomically((std::filesystem::path(folder) / "render.json").string(), render_json(record));
}

}  // namespace mipnerf::eval
