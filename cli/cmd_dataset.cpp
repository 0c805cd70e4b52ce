// `mipnerf-cl dataset inspect DIR`: loads a dataset and prints what it holds, per split and scale, with the
// camera geometry (centre bounds, the look-at point of inward-looking cameras, the viewing direction of a
// forward-facing capture) that makes a convention mistake visible at once.
// `mipnerf-cl dataset import-colmap SPARSE_DIR IMAGES_DIR OUT`: a COLMAP sparse model → OUT/transforms.json.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>

#include "common.hpp"
#include "core/error.hpp"
#include "core/lens_models.hpp"
#include "core/stage_options.hpp"
#include "data/import/colmap_import.hpp"
#include "data/dataset.hpp"
#include "data/formats/formats.hpp"
#include "data/inspect.hpp"
#include "dataset_import.hpp"
#include "train/config.hpp"

namespace mipnerf::cli {
namespace {

struct InspectArgs {
  std::string path;
  int scales = 1;
  std::string factor = "1";  // read as train reads its factor setting (train_factor)
  std::string background;  // empty: what train would choose for the scene; else parsed by its name table
  std::optional<bool> spherify;  // unset: what train would choose
  double near = 0.0, far = 0.0;
  std::vector<std::string> splits;
};

std::string num(double v, int precision = 3) {
  char text[48];
  std::snprintf(text, sizeof(text), "%.*g", precision, v);
  return text;
}

// "a" when low == high (to the printed precision), else "a … b".
std::string range(double low, double high, int precision = 4) {
  const std::string a = num(low, precision), b = num(high, precision);
  return a == b ? a : a + " .. " + b;
}

// Fixed decimals, so a look-at point at the origin reads (0.000, 0.000, 0.000) and not 1e-17s.
std::string vec(const Vec3& v) {
  auto unsigned_zero = [](double x) { return std::abs(x) < 5e-4 ? 0.0 : x; };  // no "-0.000"
  char text[96];
  std::snprintf(text, sizeof(text), "(%.3f, %.3f, %.3f)", unsigned_zero(v[0]), unsigned_zero(v[1]),
                unsigned_zero(v[2]));
  return text;
}

// Where a split's cameras look. An inward-looking capture's optical axes meet at its look-at centre, in front of every
// camera unless a pose is wrong. A forward-facing capture's nearly parallel axes meet far away or behind the cameras,
// which says nothing about its poses: it shows its viewing direction, and its look-at centre only where that lies in
// front of every camera.
void print_where_cameras_look(const data::SplitSummary& s, bool ndc) {
  const bool centre_in_front = s.look_at && s.cameras_facing == s.images;
  if (s.forward_facing) {
    char spread[32];
    std::snprintf(spread, sizeof(spread), "%.1f", s.axis_spread_deg);
    std::cout << "  viewing direction (the mean optical axis): " << vec(s.view_direction) << ", every axis within "
              << spread << " degrees of it: a forward-facing capture, whose axes need not meet"
              << (centre_in_front ? "" : " (so no look-at centre)") << "\n";
    if (!centre_in_front) return;
  }
  if (!s.look_at) {
    std::cout << "  look-at centre: undefined (all optical axes are parallel)\n";
    return;
  }
  std::cout << "  look-at centre (closest to all optical axes): " << vec(*s.look_at) << ", in front of "
            << s.cameras_facing << "/" << s.images << " cameras at depth "
            << range(s.look_at_depth_min, s.look_at_depth_max) << ", every axis passes within " << num(s.axis_miss_max)
            << " of it\n";
  if (s.cameras_facing < s.images) {
    std::cout << "  WARNING: " << s.images - s.cameras_facing
              << " cameras look away from the look-at centre: are the poses camera-to-world, in OpenGL/Blender "
                 "axes (x right, y up, looking down -z)?\n";
  } else if (!ndc && (s.look_at_depth_min < s.near_min || s.look_at_depth_max > s.far_max)) {
    std::cout << "  WARNING: the look-at centre lies outside near..far for some cameras: check near/far\n";
  }
}

void print_split(const data::SplitSummary& s, bool ndc) {
  const std::string pixels = s.pixels < 1000000 ? std::to_string(s.pixels) : num(s.pixels / 1e6) + " M";
  std::cout << "split " << s.name << ": " << s.images << " images, " << pixels << " pixels  ("
            << s.source << ")\n";
  for (const auto& level : s.scales) {
    const std::string size = level.width_min == level.width_max && level.height_min == level.height_max
                                 ? std::to_string(level.width_min) + "x" + std::to_string(level.height_min)
                                 : std::to_string(level.width_min) + ".." + std::to_string(level.width_max) + "x" +
                                       std::to_string(level.height_min) + ".." + std::to_string(level.height_max);
    std::cout << "  scale " << level.level << " (/" << (1u << level.level) << "): " << level.images << " images "
              << size << ", focal x " << range(level.focal_x_min, level.focal_x_max, 6) << " px, focal y "
              << range(level.focal_y_min, level.focal_y_max, 6) << " px, lossmult "
              << range(level.lossmult_min, level.lossmult_max) << "\n";
  }
  std::cout << "  near " << range(s.near_min, s.near_max) << ", far " << range(s.far_min, s.far_max)
            << (ndc ? " (NDC: the near plane to infinity)" : "") << "\n";
  std::cout << "  camera centres: x " << range(s.center_min[0], s.center_max[0]) << ", y "
            << range(s.center_min[1], s.center_max[1]) << ", z " << range(s.center_min[2], s.center_max[2])
            << "; distance from the origin " << range(s.radius_min, s.radius_max) << "\n";
  print_where_cameras_look(s, ndc);
  for (const auto& lens : s.lenses) std::cout << "  lens: " << lens << "\n";
  std::cout << "  mean colour " << vec({s.mean_rgb[0], s.mean_rgb[1], s.mean_rgb[2]}) << "\n";
}

Background parse_background_flag(const std::string& value) {
  const std::optional<Background> parsed = enum_from_name<Background>(value);
  if (!parsed) throw Error("--background '" + value + "': expected " + enum_choices<Background>());
  return *parsed;
}

// --factor as train reads its `factor` setting: the same parser and rule, so the two flags take the same values.
uint32_t train_factor(const std::string& text) {
  return static_cast<uint32_t>(train::resolve_config("paper", "mipnerf", {{"factor", text}}).factor);
}

// The load options `train` would use for the dataset: the effects its scene calls for (data/formats), and any
// explicit flag instead. `scene_line` becomes train's "scene: …" line.
data::LoadOptions train_like_options(const InspectArgs& args, std::string& scene_line) {
  data::LoadOptions options;
  options.factor = train_factor(args.factor);
  const data::SceneEffects effects = data::scene_effects(args.path, options);
  auto effect = [&effects](const char* name, const char* otherwise) {
    const auto found = effects.settings.find(name);
    return found == effects.settings.end() ? std::string(otherwise) : found->second;
  };
  options.background = parse_background_flag(args.background.empty() ? effect("background", "white") : args.background);
  options.llff.spherify = args.spherify ? *args.spherify : effect("spherify", "false") == "true";
  options.llff.ndc = effect("ray_shape", "cone") == "cylinder";
  options.forward_facing_ndc = options.llff.ndc;
  scene_line = "scene: " + effects.summary;
  if (!args.background.empty() || args.spherify) scene_line += " (flags given here win)";
  if (!effects.mipnerf_summary.empty()) scene_line += "; mip-NeRF: " + effects.mipnerf_summary;
  if (!effects.zipnerf_summary.empty()) scene_line += "; with --model zipnerf: " + effects.zipnerf_summary;
  return options;
}

void run_inspect(const InspectArgs& args) {
  std::string scene_line;
  data::LoadOptions options = train_like_options(args, scene_line);
  options.scales = args.scales;
  if (args.near > 0.0) options.near = args.near;
  if (args.far > 0.0) options.far = args.far;
  options.splits = args.splits;
  options.log = print_log;
  const data::Dataset dataset = data::load_dataset(args.path, options);
  std::cout << "dataset " << dataset.path << "\n"
            << "format " << data::format_name(dataset.format) << ", background " << enum_name(options.background)
            << (options.factor > 1 ? ", factor " + std::to_string(options.factor) : "")
            << (args.scales > 1 ? ", " + std::to_string(args.scales) + " scales built on the fly" : "") << "\n"
            << scene_line << "\n";
  for (const auto& split : dataset.splits) {
    const data::SplitSummary summary = data::summarize(split);
    // An NDC capture's near 0, far 1 (LLFF's, a forward-facing transforms.json's) are NDC bounds, not depths the
    // look-at centre could be compared with.
    const bool ndc = data::format_reader(dataset.format).ndc_bounds || options.forward_facing_ndc;
    print_split(summary, ndc && summary.near_max == 0 && summary.far_min == 1);
  }
}

struct ImportColmapArgs {
  std::string sparse_dir, images_dir, out;
  double near = 0.0, far = 0.0;
  std::string layout = "auto";
};

}  // namespace

data::ImportLayout parse_import_layout(const std::string& value) {
  if (value == "auto") return data::ImportLayout::automatic;
  if (value == "llff") return data::ImportLayout::llff;
  if (value == "transforms") return data::ImportLayout::transforms_json;
  throw Error("--layout '" + value + "': expected auto, llff or transforms");
}

void print_import(const data::ColmapImport& imported, const std::string& sparse_dir) {
  std::string models;
  for (const auto& name : imported.camera_models) models += (models.empty() ? "" : ", ") + name;
  const bool llff = imported.layout == data::ImportLayout::llff;
  std::cout << "imported " << imported.images << " images (" << imported.cameras
            << (imported.cameras == 1 ? " camera: " : " cameras: ") << models << ") and " << imported.points
            << " points from " << sparse_dir << " (" << (imported.binary ? "binary" : "text") << ") into "
            << (llff ? imported.dataset_path + " (LLFF: poses_bounds.npy, images/)" : imported.transforms_path) << "\n";
  std::cout << "layout: " << (llff ? "LLFF" : "transforms.json") << ", " << imported.layout_reason << "\n";
  if (llff) {
    std::cout << "bounds per image from its points' depths (0.1th and 99.9th percentile): " << num(imported.near, 4)
              << " .. " << num(imported.far, 4) << " (COLMAP units; the LLFF loader rescales them)\n";
  } else {
    const char* rule = imported.centre_rule == "look-at"  ? "the point closest to every optical axis"
                       : imported.centre_rule == "points" ? "the median of the sparse points"
                                                          : "the mean camera centre";
    std::cout << "world: COLMAP's " << vec(imported.centre) << " (" << rule << ") is the origin, scaled by "
              << num(imported.scale, 4) << " (the median camera " << num(data::kImportedCameraDistance)
              << " from it)\n";
    std::cout << "near " << num(imported.near, 4) << ", far " << num(imported.far, 4)
              << (imported.near_far_from_points ? " (from the points' depths)" : " (as given)") << "\n";
  }
  std::cout << "train on it: mipnerf-cl train --data " << imported.dataset_path << " --out runs/NAME\n";
}

namespace {

void run_import_colmap(const ImportColmapArgs& args) {
  data::ColmapImportOptions options;
  if (args.near > 0.0) options.near = args.near;
  if (args.far > 0.0) options.far = args.far;
  options.layout = parse_import_layout(args.layout);
  print_import(data::import_colmap(args.sparse_dir, args.images_dir, args.out, options), args.sparse_dir);
}

}  // namespace

void register_dataset(CLI::App& app) {
  auto* cmd = app.add_subcommand("dataset", "Datasets: inspect what a dataset folder holds, import a COLMAP model");
  cmd->require_subcommand(1);
  auto args = std::make_shared<InspectArgs>();
  auto* inspect = cmd->add_subcommand(
      "inspect",
      "Load a dataset (Blender, multiscale Blender, transforms.json or an LLFF capture) and print its splits, image "
      "sizes per scale, focal lengths, near/far, camera-centre bounds and where the cameras look (the look-at centre, "
      "or a forward-facing capture's viewing direction)");
  inspect
      ->add_option("DIR", args->path,
                   "Dataset folder (an LLFF capture: poses_bounds.npy and images/), transforms.json or metadata.json")
      ->required();
  inspect->add_option("--scales", args->scales, "Build this many scales on the fly (the paper's multiscale: 4)")
      ->check(CLI::Range(1, 8));
  // The training setting's help: the dataset composites its images exactly as training does.
  inspect->add_option("--background", args->background,
                      "white | black | none; default: what train would choose for the scene (its effects)");
  // train's factor setting, as its flag reads it (type, help and rule: train_factor).
  const train::Setting& factor = train::find_setting("factor");
  inspect->add_option("--factor", args->factor, factor.help + "; LLFF: reads images_<factor>/ when present")
      ->type_name(factor.type);
  inspect
      ->add_option("--spherify", args->spherify,
                   "LLFF: true re-poses a 360° capture around its centre; default: what train would choose")
      ->type_name(train::find_setting("spherify").type);
  inspect->add_option("--near", args->near, "Override near (depth along the optical axis)")
      ->check(CLI::PositiveNumber);
  inspect->add_option("--far", args->far, "Override far")->check(CLI::PositiveNumber);
  inspect->add_option("--split", args->splits, "Only these splits (train, val, test); default: all present");
  inspect->callback([args] { run_inspect(*args); });

  auto import_args = std::make_shared<ImportColmapArgs>();
  auto* import = cmd->add_subcommand(
      "import-colmap",
      "Convert a COLMAP sparse model (cameras, images, points3D; .bin or .txt) of " + lens_model_list("or") +
          " cameras (several may mix; lenses are kept) into a dataset train, render and eval read: a forward-facing "
          "capture of one pinhole camera as an LLFF capture (OUT/poses_bounds.npy, OUT/images/), anything else as "
          "OUT/transforms.json (poses to OpenGL axes, the world recentred and scaled, near/far from the sparse points)");
  import->add_option("SPARSE_DIR", import_args->sparse_dir, "The model's folder (e.g. undistorted/sparse)")->required();
  import
      ->add_option("IMAGES_DIR", import_args->images_dir,
                   "Its images, PNG or JPEG (e.g. undistorted/images); referenced, not copied")
      ->required();
  import->add_option("OUT", import_args->out, "Output folder (created)")->required();
  import->add_option("--layout", import_args->layout,
                     "auto (LLFF for a forward-facing capture of one pinhole camera, else transforms.json), llff or "
                     "transforms")
      ->capture_default_str();
  import->add_option("--near", import_args->near, "Override near (scene units, after scaling)")
      ->check(CLI::PositiveNumber);
  import->add_option("--far", import_args->far, "Override far (scene units)")->check(CLI::PositiveNumber);
  import->callback([import_args] { run_import_colmap(*import_args); });
  register_from_photos(*cmd);
}

}  // namespace mipnerf::cli
