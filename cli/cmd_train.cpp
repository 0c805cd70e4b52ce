// `mipnerf-cl train`: train a scene (the built-in procedural one by default), then render and score the
// val views, so a run ends with an image, a number, and what it cost.
#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "common.hpp"
#include "data/procedural.hpp"
#include "eval/evaluate.hpp"
#include "io/atomic_file.hpp"
#include "io/png.hpp"
#include "mlp/gemm_tuning.hpp"
#include "mlp/mlp_config.hpp"
#include "progress.hpp"
#include "train/trainer.hpp"

namespace mipnerf::cli {
namespace fs = std::filesystem;
namespace {

struct TrainArgs {
  std::string data;
  std::string out = "runs/train";
  std::string preset = "quick";
  std::string variant = "mipnerf";
  bool resume = false;
  std::string config_file;                // --config FILE
  std::vector<std::string> sets;          // --set name=value
  std::map<std::string, std::string> flag_values;  // --<setting> value
};

std::atomic<bool> g_stop_requested{false};

extern "C" void on_interrupt(int) {
  if (g_stop_requested.exchange(true)) _exit(130);  // a second Ctrl-C stops at once
}

// Settings from a TOML/INI file (CLI11's parser): `name = value` at the top level or in a [train] table.
std::map<std::string, std::string> config_file_settings(const std::string& path) {
  std::vector<CLI::ConfigItem> items;
  try {
    items = CLI::ConfigTOML().from_file(path);
  } catch (const CLI::Error& e) {
    throw Error("--config " + path + ": " + e.what());
  }
  std::map<std::string, std::string> out;
  for (const auto& item : items) {
    if (item.name == "++" || item.name == "--") continue;  // CLI11's section markers
    const bool in_train = item.parents.size() == 1 && item.parents[0] == "train";
    if (!item.parents.empty() && !in_train) {
      throw Error("--config " + path + ": '" + item.fullname() + "' is outside a [train] table");
    }
    std::string value;
    for (const auto& input : item.inputs) value += (value.empty() ? "" : ",") + input;
    try {
      train::TrainConfig probe;
      train::set_value(probe, item.name, value);  // unknown names and bad values are refused here, by file
    } catch (const Error& e) {
      throw Error("--config " + path + ": " + e.what());
    }
    out[item.name] = value;
  }
  return out;
}

// The settings given explicitly: the config file, then flags, then --set (later ones win).
std::map<std::string, std::string> explicit_settings(const TrainArgs& args, CLI::App& cmd) {
  std::map<std::string, std::string> out;
  if (!args.config_file.empty()) out = config_file_settings(args.config_file);
  for (const auto& s : train::settings()) {
    auto* option = cmd.get_option_no_throw("--" + s.name);
    if (option != nullptr && option->count() > 0) out[s.name] = option->as<std::string>();
  }
  for (const auto& assignment : args.sets) {
    const auto eq = assignment.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw Error("--set '" + assignment + "': expected name=value, e.g. --set num_samples=64");
    }
    out[assignment.substr(0, eq)] = assignment.substr(eq + 1);
  }
  return out;
}

// The quick start's scene: made once inside the output folder, reused afterwards.
std::string default_scene(const std::string& out_dir) {
  const fs::path scene = fs::path(out_dir) / "scene";
  if (!fs::exists(scene / "transforms_train.json")) {
    std::cerr << "mipnerf-cl: no --data given: generating the built-in procedural scene in " << scene.string() << "\n";
    data::write_procedural_scene(scene.string(), data::SceneOptions{});
  }
  return scene.string();
}

void write_summary(const std::string& out_dir, const train::Trainer& trainer, const train::TrainResult& result,
                   const eval::SplitScores* val, const std::string& device) {
  nlohmann::ordered_json j;
  j["device"] = device;
  j["steps"] = result.last_step;
  j["interrupted"] = result.interrupted;
  j["train_seconds"] = result.train_seconds;
  j["skipped_steps"] = result.skipped_steps;
  j["parameters"] = trainer.parameter_count();
  j["chunk_rays"] = trainer.memory().chunk_rays;
  j["planned_device_bytes"] = trainer.memory().total();
  j["checkpoint"] = result.checkpoint;
  if (val) {
    j["val"]["views"] = val->images.size();
    j["val"]["mean_psnr"] = val->mean_psnr;
    j["val"]["mean_ssim"] = val->mean_ssim;
    j["val"]["render_seconds_per_megapixel"] = val->seconds_per_megapixel();
    for (const auto& s : val->scales) {
      j["val"]["scales"].push_back({{"scale_level", s.scale_level}, {"images", s.images},
                                    {"mean_psnr", s.mean_psnr}, {"mean_ssim", s.mean_ssim}});
    }
  }
  io::write_bytes_atomically((fs::path(out_dir) / "summary.json").string(), j.dump(2) + "\n");
}

eval::SplitScores evaluate_val(ocl::Context& ctx, train::Trainer& trainer, const std::string& data_path,
                               const std::string& out_dir) {
  const auto& c = trainer.config();
  const data::Dataset val_data = data::load_dataset(data_path, train::load_options(c, data_path, {"val"}));
  const data::Split& val = val_data.split("val");
  std::vector<mlp::Mlp*> networks;
  for (auto& n : trainer.networks()) networks.push_back(n.get());
  eval::ImageRenderer renderer(ctx, trainer.spec(), networks, val.cameras, static_cast<size_t>(c.render_chunk_rays));
  const fs::path folder = fs::path(out_dir) / "val";
  eval::EvaluateOptions options;
  options.max_views = static_cast<size_t>(c.val_views);
  const size_t total = eval::select_views(val, options.max_views).size();
  Progress progress("render val", static_cast<int64_t>(total));
  options.progress = [&](size_t done, size_t) { progress.update(static_cast<int64_t>(done)); };
  options.on_image = [&](const eval::ImageScore& score, const eval::RenderedImage& image, const float*) {
    char name[64];
    std::snprintf(name, sizeof(name), "%03zu_scale%u.png", score.index, score.scale_level);
    io::write_png((folder / name).string(), image.width, image.height, 3, image.rgb.data());
  };
  const auto scores = eval::evaluate_split(renderer, val, options);
  progress.finish();
  return scores;
}

void run_train(TrainArgs& args, CLI::App& cmd) {
  const auto settings = explicit_settings(args, cmd);
  const train::TrainConfig config = train::resolve_config(args.preset, args.variant, settings);
  const std::string data_path = args.data.empty() ? default_scene(args.out) : args.data;
  auto ctx = open_context();
  const std::string device = ctx->device_info().name;

  train::Trainer trainer(*ctx, config, data_path, args.out, args.resume);
  mlp::load_gemm_tuning(*ctx);  // after the inputs are checked, before the first product
  const auto& spec = trainer.spec();
  std::cerr << "mipnerf-cl: training " << enum_name(config.variant) << " (preset " << args.preset << ") on " << device
            << ": " << trainer.dataset().split("train").num_images() << " images, " << trainer.parameter_count()
            << " parameters, " << spec.describe() << "\n"
            << "mipnerf-cl: " << trainer.memory().describe() << "\n";

  g_stop_requested = false;
  auto previous_handler = std::signal(SIGINT, on_interrupt);
  Progress progress("train", config.steps);
  train::TrainHooks hooks;
  hooks.should_stop = [] { return g_stop_requested.load(); };
  hooks.on_step = [&](const train::StepReport& r) {
    char detail[160];
    std::snprintf(detail, sizeof(detail), "loss %.5f  psnr %.2f dB  lr %.2e  %.0f rays/s%s", r.loss, r.psnr,
                  r.learning_rate, r.rays_per_second, r.skipped ? "  (skipped: non-finite)" : "");
    progress.update(r.step, detail);
  };
  const train::TrainResult result = trainer.run(hooks);
  std::signal(SIGINT, previous_handler);
  progress.finish();
  if (result.interrupted) {
    std::cerr << "mipnerf-cl: interrupted at step " << result.last_step << "; checkpoint " << result.checkpoint
              << " (continue with --resume)\n";
    write_summary(args.out, trainer, result, nullptr, device);
    return;
  }
  std::cerr << "mipnerf-cl: trained " << result.last_step << " steps in " << format_duration(result.train_seconds)
            << " on " << device << "; checkpoint " << result.checkpoint << "\n";

  const eval::SplitScores* val_scores = nullptr;
  eval::SplitScores scores;
  try {
    scores = evaluate_val(*ctx, trainer, data_path, args.out);
    val_scores = &scores;
  } catch (const Error& e) {
    std::cerr << "mipnerf-cl: warning: no val evaluation: " << e.what() << "\n";
  }
  write_summary(args.out, trainer, result, val_scores, device);
  if (val_scores) {
    std::printf("val PSNR %.2f dB, SSIM %.4f over %zu images; trained %lld steps in %.1f s; rendering %.2f s/MP on %s\n",
                scores.mean_psnr, scores.mean_ssim, scores.images.size(), static_cast<long long>(result.last_step),
                result.train_seconds, scores.seconds_per_megapixel(), device.c_str());
    std::printf("images in %s, summary in %s\n", (fs::path(args.out) / "val").string().c_str(),
                (fs::path(args.out) / "summary.json").string().c_str());
  }
}

}  // namespace

void register_train(CLI::App& app) {
  auto args = std::make_shared<TrainArgs>();
  auto* cmd = app.add_subcommand("train", "Train mip-NeRF (or a variant) on a scene, then score its val views");
  cmd->add_option("--data", args->data, "Scene folder (Blender, multiscale Blender or transforms.json); "
                                        "default: the built-in procedural scene, made in OUT/scene");
  cmd->add_option("--out", args->out, "Output folder: checkpoints, logs, config, val renders")->capture_default_str();
  cmd->add_option("--preset", args->preset, "Settings bundle: " + train::describe_bundles())->capture_default_str();
  cmd->add_option("--variant", args->variant,
                  "Model variant, a row of the paper's tables: " + enum_choices<train::Variant>() +
                      " (recorded in OUT/config.json as variant_bundle)")
      ->capture_default_str();
  cmd->add_flag("--resume", args->resume, "Continue from the newest checkpoint in OUT/checkpoints");
  cmd->add_option("--set", args->sets, "Any setting as name=value (repeatable)");
  cmd->add_option("--config", args->config_file,
                  "TOML/INI file of settings, e.g. `num_samples = 64` (top level or a [train] table); flags win")
      ->check(CLI::ExistingFile);
  for (const auto& s : train::settings()) {
    if (s.name == "variant") continue;  // set through --variant, which also applies the variant's bundle
    cmd->add_option("--" + s.name)->description("[" + s.group + "] " + s.help)->type_name("VALUE");
  }
  cmd->callback([args, cmd] { run_train(*args, *cmd); });
}

}  // namespace mipnerf::cli
