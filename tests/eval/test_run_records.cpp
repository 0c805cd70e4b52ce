// The records of a run that eval/report.hpp builds: summary.json of training (with and without val scores) and
// render.json of a render, key by key in their reading order.
#include <doctest/doctest.h>

#include <string>
#include <vector>

#include "eval/report.hpp"

using namespace mipnerf;

namespace {

std::vector<std::string> keys_of(const nlohmann::ordered_json& j) {
  std::vector<std::string> keys;
  for (const auto& item : j.items()) keys.push_back(item.key());
  return keys;
}

}  // namespace

TEST_CASE("run records: summary.json holds the run, and the val scores when there are some") {
  eval::TrainRecord record;
  record.device = "dev";
  record.parameters = 1234;
  record.chunk_rays = 256;
  record.planned_device_bytes = 1 << 20;
  train::TrainResult result;
  result.last_step = 40;
  result.interrupted = true;
  result.train_seconds = 2.5;
  result.skipped_steps = 1;
  result.checkpoint = "run/checkpoints/ckpt_000000040.mnck";
  const std::vector<std::string> run_keys = {"device",        "steps",      "interrupted", "train_seconds",
                                             "skipped_steps", "parameters", "chunk_rays",  "planned_device_bytes",
                                             "checkpoint"};
  const auto interrupted = eval::summary_json(record, result, nullptr);
  CHECK(keys_of(interrupted) == run_keys);
  CHECK(interrupted["steps"] == 40);
  CHECK(interrupted["interrupted"] == true);
  CHECK(interrupted["planned_device_bytes"] == 1 << 20);
  CHECK(interrupted["checkpoint"] == result.checkpoint);

  eval::SplitScores val;
  val.images.resize(3);
  val.mean_psnr = 21.5;
  val.mean_ssim = 0.75;
  val.render_seconds = 4.0;
  val.megapixels = 2.0;
  eval::ScaleSummary scale;
  scale.scale_level = 1;
  scale.images = 3;
  scale.mean_psnr = 21.5;
  scale.mean_ssim = 0.75;
  val.scales.push_back(scale);
  result.interrupted = false;
  const auto finished = eval::summary_json(record, result, &val);
  auto with_val = run_keys;
  with_val.push_back("val");
  CHECK(keys_of(finished) == with_val);
  CHECK(keys_of(finished["val"]) ==
        std::vector<std::string>{"views", "mean_psnr", "mean_ssim", "render_seconds_per_megapixel", "scales"});
  CHECK(finished["val"]["views"] == 3);
  CHECK(finished["val"]["render_seconds_per_megapixel"] == 2.0);
  CHECK(finished["val"]["scales"][0]["scale_level"] == 1);
  CHECK(finished["val"]["scales"][0]["mean_ssim"] == 0.75);
}

TEST_CASE("run records: render.json holds the source, the device and the render time per megapixel") {
  eval::RenderRecord record;
  record.checkpoint = "/runs/a/checkpoints/ckpt_000000010.mnck";
  record.step = 10;
  record.source = {{"kind", "orbit"}};
  record.date = "2026-01-02T03:04:05Z";
  record.device = {{"name", "dev"}};
  record.frames = 4;
  record.formats = {true, true};
  record.rays_per_pixel = 2;
  record.chunk_rays = 512;
  record.warm_up_seconds = 0.5;
  record.render_seconds = 3.0;
  record.megapixels = 1.5;
  const auto j = eval::render_json(record);
  CHECK(keys_of(j) == std::vector<std::string>{"checkpoint", "step", "source", "date", "device", "frames", "formats",
                                               "rays_per_pixel", "chunk_rays", "warm_up_seconds", "render_seconds",
                                               "megapixels", "seconds_per_megapixel"});
  CHECK(j["formats"] == "png, exr");
  CHECK(j["source"]["kind"] == "orbit");
  CHECK(j["seconds_per_megapixel"] == 2.0);
  record.formats = {false, true};
  record.megapixels = 0.0;
  CHECK(eval::render_json(record)["formats"] == "exr");
  CHECK(eval::render_json(record)["seconds_per_megapixel"] == 0.0);
}
