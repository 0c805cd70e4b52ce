// A training run followed by the val evaluation of the networks it trained.
#include "eval/train_and_evaluate.hpp"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

#include "core/error.hpp"
#include "eval/image_output.hpp"
#include "eval/image_renderer.hpp"
#include "eval/render_setup.hpp"
#include "io/png.hpp"
#include "parallel/world.hpp"
#include "train/model.hpp"

namespace mipnerf::eval {
namespace fs = std::filesystem;
namespace {

// Writes a val render as folder/NNN_scaleK.png (view number, scale level), and beside it its ground truth (_gt)
// and error image (_error: mean |render − truth| × 4, as eval writes them), which `mipnerf-cl view` shows.
void write_val_png(const std::string& folder, const ImageScore& score, const RenderedImage& image,
                   const float* truth) {
  char stem[64];
  std::snprintf(stem, sizeof(stem), "%03zu_scale%u", score.index, score.scale_level);
  const std::string path = (fs::path(folder) / stem).string();
  io::write_png(path + ".png", image.width, image.height, 3, image.rgb.data());
  if (truth == nullptr) return;
  const size_t pixels = static_cast<size_t>(image.width) * image.height;
  io::write_png(path + "_gt.png", image.width, image.height, 3, truth);
  const std::vector<float> error = error_image(image.rgb.data(), truth, pixels, 4.0);
  io::write_png(path + "_error.png", image.width, image.height, 3, error.data());
}

// The val split as the run's configuration loads it.
data::Dataset load_val(const train::TrainConfig& c, const std::string& data_path) {
  return data::load_dataset(data_path, train::load_options(c, data_path, {"val"}));
}

std::unique_ptr<ImageRenderer> val_renderer(ocl::Context& ctx, train::Trainer& trainer, const data::Split& val) {
  const size_t chunk = static_cast<size_t>(trainer.config().render_chunk_rays);
  return std::make_unique<ImageRenderer>(
      ctx, trainer.spec(), trainer.network_pointers(), trainer.grid_pointers(), val.cameras,
      RenderSettings{render_chunk_rays(trainer.spec(), chunk, ctx.device_info(), 0), 1, 0});
}

// Each val render written as the final evaluation writes it (val_image_folder; under mpirun, rank 0 writes).
void write_val_images(const TrainAndEvaluateOptions& options, EvaluateOptions& evaluate) {
  if (options.val_image_folder.empty() || !parallel::world().is_root()) return;
  const std::string folder = options.val_image_folder;
  evaluate.on_image = [folder](const ImageScore& score, const RenderedImage& image, const float* truth) {
    write_val_png(folder, score, image, truth);
  };
}

// The first config.val_views views of the val split (all: 0), rendered in chunks of config.render_chunk_rays.
SplitScores evaluate_val(ocl::Context& ctx, train::Trainer& trainer, const TrainAndEvaluateOptions& options) {
  const auto& c = trainer.config();
  const data::Dataset val_data = load_val(c, options.data_path);
  const data::Split& val = val_data.split("val");
  const std::unique_ptr<ImageRenderer> renderer = val_renderer(ctx, trainer, val);
  EvaluateOptions evaluate;
  evaluate.max_views = static_cast<size_t>(c.val_views);
  evaluate.progress = options.val_progress;
  write_val_images(options, evaluate);
  if (options.on_val_start) options.on_val_start(select_views(val, evaluate.max_views).size());
  return evaluate_split(*renderer, val, evaluate);
}

// The val scores during training (config.val_every): the val split is loaded and the renderer built at the first
// score and kept; the renderer reads the networks the trainer updates in place. The score of the last step renders
// the same views of the same networks as the final evaluation would: it writes the val images and is kept
// (last_step_scores), so a run scores its val views once at its end, not twice (a minute each on real photos and a
// CPU).
struct PeriodicVal {
  ocl::Context* ctx;
  std::string data_path;
  const TrainAndEvaluateOptions* options;  // its periodic_val callbacks, the val image folder
  std::unique_ptr<data::Dataset> val_data;
  std::unique_ptr<ImageRenderer> renderer;
  std::optional<SplitScores> last_step_scores;  // the score at config.steps, the final evaluation's

  train::ValScore operator()(train::Trainer& trainer) {
    const auto started = std::chrono::steady_clock::now();
    if (!renderer) {
      val_data = std::make_unique<data::Dataset>(load_val(trainer.config(), data_path));
      renderer = val_renderer(*ctx, trainer, val_data->split("val"));
    }
    const bool last_step = trainer.step() == trainer.config().steps;
    EvaluateOptions evaluate;
    evaluate.max_views = static_cast<size_t>(trainer.config().val_views);
    evaluate.ray_progress = options->periodic_val_progress;
    if (last_step && options->evaluate_val) write_val_images(*options, evaluate);
    if (options->on_periodic_val_start) {
      options->on_periodic_val_start(trainer.step(), select_views(val_data->split("val"), evaluate.max_views).size());
    }
    SplitScores scores = evaluate_split(*renderer, val_data->split("val"), evaluate);
    if (options->on_periodic_val_end) {
      options->on_periodic_val_end(std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
    }
    const train::ValScore score{scores.mean_psnr, scores.mean_ssim, scores.images.size()};
    if (last_step) last_step_scores = std::move(scores);
    return score;
  }
};

}  // namespace

TrainAndEvaluateResult train_and_evaluate(ocl::Context& ctx, const train::TrainConfig& config,
                                          const TrainAndEvaluateOptions& options) {
  train::Trainer trainer(ctx, config, options.data_path, options.out_dir, options.resume);
  if (options.budget_seconds > 0.0) trainer.fit_steps_to_budget(options.budget_seconds);
  if (options.on_setup) options.on_setup(trainer);
  TrainAndEvaluateResult result;
  result.record = train_record(trainer, ctx.device_info().name);
  train::TrainHooks hooks = options.hooks;
  std::shared_ptr<PeriodicVal> periodic;  // one object the hook's copies share (std::function copies its target)
  if (config.val_every > 0 && !hooks.score_val) {
    periodic = std::make_shared<PeriodicVal>(PeriodicVal{&ctx, options.data_path, &options, nullptr, nullptr, {}});
    hooks.score_val = [periodic](train::Trainer& t) { return (*periodic)(t); };
  }
  result.train = trainer.run(hooks);
  if (options.on_trained) options.on_trained(trainer, result.train);
  if (!options.evaluate_val || result.train.interrupted) return result;
  if (periodic && periodic->last_step_scores && trainer.step() == trainer.config().steps) {
    result.val = std::move(periodic->last_step_scores);  // rendered and written at the last step
    return result;
  }
  try {
    result.val = evaluate_val(ctx, trainer, options);
  } catch (const Error& e) {
    result.val_error = e.what();
  }
  return result;
}

}  // namespace mipnerf::eval
