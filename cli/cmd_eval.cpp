// `mipnerf-cl eval`: render a split (every scale of multiscale data), score each image with PSNR and SSIM as
// the paper's code does, and write metrics.json, metrics.md and the rendered, ground-truth and error images.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

#include "core/error.hpp"
#include "dist/world.hpp"
#include "common.hpp"
#include "eval/evaluate.hpp"
#include "eval/image_output.hpp"
#include "eval/render_setup.hpp"
#include "eval/report.hpp"
#include "io/atomic_file.hpp"
#include "io/png.hpp"
#include "progress.hpp"
#include "train/checkpoint.hpp"
#include "train/model.hpp"

namespace mipnerf::cli {
namespace fs = std::filesystem;
namespace {

struct EvalArgs {
  std::string checkpoint;
  std::string data;
  std::string split = "test";
  std::string out;
  size_t views = 0;
  int scales = 0;
  uint32_t supersample = 1;
  uint64_t seed = 0;
  size_t chunk = 0;
  double error_gain = 4.0;
  bool no_images = false;
  bool exr = false;
};

void check_arguments(const EvalArgs& args, const CLI::App& cmd) {
  check_view_options(cmd, args.views, args.scales, args.supersample);
  if (!(args.error_gain > 0.0)) throw Error("--error-gain must be positive");
}

void run_eval(const EvalArgs& args, const CLI::App& cmd) {
  check_arguments(args, cmd);
  const std::string found = train::find_checkpoint(args.checkpoint);
  const std::string checkpoint = fs::absolute(found).lexically_normal().string();  // for the records
  auto ctx = open_context();
  const train::TrainedModel model = train::load_trained_model(*ctx, checkpoint);
  const std::string data_path = eval::resolve_data_path(args.data, model, checkpoint);
  const data::Dataset dataset =
      data::load_dataset(data_path, train::load_options(model.config, data_path, {args.split}, args.scales));
  const data::Split& split = dataset.split(args.split);
  const size_t chunk = eval::render_chunk_rays(model, ctx->device_info(), args.chunk);
  const std::string out =
      args.out.empty() ? (fs::path(eval::run_folder_of(found)) / ("eval_" + args.split)).string() : args.out;
  const fs::path images = fs::path(out) / "images";
  const std::vector<std::string> stems = eval::split_image_stems(split);

  prepare_gemm_for_rendering(*ctx);
  eval::ImageRenderer renderer(*ctx, model.spec, model.network_pointers(), split.cameras,
                               eval::RenderSettings{chunk, args.supersample, args.seed});
  const double warm_up = renderer.warm_up();

  eval::EvaluateOptions options;
  options.max_views = args.views;
  size_t total_rays = 0;
  for (size_t i : eval::select_views(split, args.views)) {
    total_rays += static_cast<size_t>(split.cameras[i].width_px) * split.cameras[i].height_px * args.supersample;
  }
  Progress progress("eval " + args.split, static_cast<int64_t>(total_rays));
  progress.update(0);  // the rate (and ETA) counts from here, not from the first chunk
  size_t images_done = 0, images_total = eval::select_views(split, args.views).size();
  options.ray_progress = [&](size_t done, size_t) {
    progress.update(static_cast<int64_t>(done), "image " + std::to_string(std::min(images_done + 1, images_total)) +
                                                    "/" + std::to_string(images_total));
  };
  options.progress = [&](size_t done, size_t) { images_done = done; };
  if (!args.no_images && dist::world().is_root()) {  // under mpirun, rank 0 writes
    options.on_image = [&](const eval::ImageScore& score, const eval::RenderedImage& image, const float* truth) {
      const std::string stem = (images / stems[score.index]).string();
      eval::write_rendered_image(stem, image, {true, args.exr});
      io::write_png(stem + "_gt.png", image.width, image.height, 3, truth);
      const auto error =
          eval::error_image(image.rgb.data(), truth, static_cast<size_t>(image.width) * image.height, args.error_gain);
      io::write_png(stem + "_error.png", image.width, image.height, 3, error.data());
    };
  }
  const eval::SplitScores scores = eval::evaluate_split(renderer, split, options);
  progress.finish();
  if (!dist::world().is_root()) return;  // every rank scored the gathered images alike; rank 0 reports

  eval::EvalRecord record;
  record.checkpoint = checkpoint;
  record.step = model.step;
  record.train_seconds = model.train_seconds;
  record.trained_on = model.trained_on;
  record.data = fs::absolute(data_path).lexically_normal().string();
  record.split = args.split;
  record.date = eval::utc_timestamp();
  record.device = eval::device_record(ctx->device_info());
  record.model = {{"variant", enum_name(model.config.variant)},
                  {"parameters", eval::parameter_count(model)},
                  {"config", train::config_json(model.config)}};
  record.supersample = args.supersample;
  record.chunk_rays = chunk;
  record.warm_up_seconds = warm_up;
  record.image_folder = args.no_images ? "" : "images";
  record.image_stems = stems;
  auto metrics = eval::metrics_json(scores, record);
  if (!args.no_images) {
    char gain[32];
    std::snprintf(gain, sizeof(gain), "%g", args.error_gain);
    metrics["error_images"] = std::string("mean |render - ground truth| over RGB, times ") + gain + ", clamped to 1";
  }
  io::write_bytes_atomically((fs::path(out) / "metrics.json").string(), metrics.dump(2) + "\n");
  io::write_bytes_atomically((fs::path(out) / "metrics.md").string(), eval::metrics_markdown(scores, record));

  std::printf("%s split of %s, step %lld, on %s:\n%s", args.split.c_str(), data_path.c_str(),
              static_cast<long long>(model.step), ctx->device_info().name.c_str(),
              eval::scale_table_markdown(scores).c_str());
  std::printf("mean PSNR %.2f dB, SSIM %.4f over %zu images; %.2f s/MP; metrics in %s\n", scores.mean_psnr,
              scores.mean_ssim, scores.images.size(), scores.seconds_per_megapixel(),
              (fs::path(out) / "metrics.json").string().c_str());
}

}  // namespace

void register_eval(CLI::App& app) {
  auto args = std::make_shared<EvalArgs>();
  auto* cmd = app.add_subcommand("eval",
                                 "Score a checkpoint on a split (PSNR, SSIM per image and per scale, render time) "
                                 "and write metrics.json, metrics.md and the images");
  cmd->add_option("--checkpoint", args->checkpoint, "A .mnck checkpoint, or a training --out folder (its newest)")
      ->required();
  cmd->add_option("--data", args->data, "Dataset (default: the one the checkpoint was trained on)");
  cmd->add_option("--split", args->split, "Split to score")->capture_default_str();
  cmd->add_option("--out", args->out, "Output folder (default: RUN/eval_<split>)");
  cmd->add_option("--views", args->views, "Only the first N views (all their scales)");
  cmd->add_option("--scales", args->scales, "Build the multiscale pyramid with N scales (default: as trained)");
  cmd->add_option("--supersample", args->supersample, "Jittered rays per pixel, averaged")->capture_default_str();
  cmd->add_option("--seed", args->seed, "Seed of the supersampling jitter")->capture_default_str();
  cmd->add_option("--chunk", args->chunk, "Rays per chunk (default: render_chunk_rays, lowered to fit the device)");
  cmd->add_option("--error-gain", args->error_gain, "Error images show mean |error| times this")->capture_default_str();
  cmd->add_flag("--exr", args->exr, "Also write each render as OpenEXR (linear RGB, depth, accumulation)");
  cmd->add_flag("--no-images", args->no_images, "Write only metrics.json and metrics.md");
  cmd->callback([args, cmd] { run_eval(*args, *cmd); });
}

}  // namespace mipnerf::cli
