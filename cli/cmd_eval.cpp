// `mipnerf-cl eval`: render a split (every scale of multiscale data), score each image with PSNR and SSIM as
// the paper's code does, and write metrics.json, metrics.md and the rendered, ground-truth and error images.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

#include "core/error.hpp"
#include "parallel/world.hpp"
#include "common.hpp"
#include "eval/evaluate.hpp"
#include "eval/image_output.hpp"
#include "eval/render_job.hpp"
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
  const std::string out =
      args.out.empty() ? (fs::path(eval::run_folder_of(found)) / ("eval_" + args.split)).string() : args.out;
  Progress progress("eval " + args.split, 0);
  eval::RenderJob job;
  job.model = &model;
  job.checkpoint = checkpoint;
  job.chunk_rays = args.chunk;
  job.supersample = args.supersample;
  job.seed = args.seed;
  job.progress = progress.job_callback();
  eval::ScoreOptions options;
  options.views = args.views;
  options.images = !args.no_images;
  options.exr = args.exr;
  options.error_gain = args.error_gain;
  const eval::SplitScores scores = eval::score_split(*ctx, job, split, data_path, out, options);
  progress.finish();
  if (!parallel::world().is_root()) return;

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
