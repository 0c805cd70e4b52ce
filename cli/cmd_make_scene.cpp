// `mipnerf-cl make-scene OUT`: writes the built-in procedural scene (Blender format, plus OUT/multiscale), or with
// --forward-facing its forward-facing capture, or with --unbounded its 360° capture outdoors, in the LLFF layout.
#include <chrono>
#include <cstdio>
#include <cmath>
#include <iostream>
#include <memory>

#include "common.hpp"
#include "core/error.hpp"
#include "core/lens_models.hpp"
#include "data/synthetic/forward_facing.hpp"
#include "data/synthetic/procedural.hpp"
#include "data/synthetic/unbounded.hpp"

namespace mipnerf::cli {

namespace {

// "SIMPLE_RADIAL:k1, RADIAL:k1,k2, …": what --lens takes, from the lens rows that have coefficients.
std::string lens_shapes() {
  std::string text;
  for (const auto& row : lens_rows()) {
    if (row.coefficients.empty()) continue;
    text += (text.empty() ? "" : ", ") + std::string(row.colmap_name) + ":";
    for (size_t i = 0; i < row.coefficients.size(); ++i) text += (i ? "," : "") + std::string(row.coefficients[i].name);
  }
  return text;
}

// --lens MODEL:c1,c2,...: the model's coefficients in COLMAP's order (core/lens_models.hpp).
Lens parse_lens(const std::string& text) {
  const auto colon = text.find(':');
  const std::string model = text.substr(0, colon);
  std::vector<double> values;
  if (colon != std::string::npos) {
    std::string rest = text.substr(colon + 1);
    for (size_t start = 0; start <= rest.size();) {
      const size_t comma = std::min(rest.find(',', start), rest.size());
      try {
        size_t used = 0;
        values.push_back(std::stod(rest.substr(start, comma - start), &used));
        if (used != comma - start) throw std::invalid_argument("trailing text");
      } catch (const std::exception&) {
        throw Error("--lens '" + text + "': '" + rest.substr(start, comma - start) + "' is not a number");
      }
      start = comma + 1;
    }
  }
  const LensRow* row = find_lens_row(model);
  if (!row || row->coefficients.empty()) {
    throw Error("--lens '" + text + "': expected one of " + lens_shapes());
  }
  if (values.size() != row->coefficients.size()) {
    throw Error("--lens '" + text + "': " + row->colmap_name + " takes " + std::to_string(row->coefficients.size()) +
                " coefficients");
  }
  return make_lens(*row, values, "--lens '" + text + "'");
}

}  // namespace

void register_make_scene(CLI::App& app) {
  auto out = std::make_shared<std::string>();
  auto options = std::make_shared<data::SceneOptions>();
  auto* cmd = app.add_subcommand(
      "make-scene",
      "Render the built-in procedural scene (checkered sphere, striped boxes; anti-aliased by jittered "
      "supersampling) into OUT in the Blender format, with OUT/multiscale holding its multiscale version");
  cmd->add_option("OUT", *out, "Output folder (created; existing files of the same names are replaced)")->required();
  cmd->add_option("--size", options->size_px, "Image width and height in pixels")->capture_default_str();
  cmd->add_option("--views", options->train_views, "Training views (random, upper hemisphere)")->capture_default_str();
  cmd->add_option("--val-views", options->val_views, "Validation views (orbit at 25 degrees)")->capture_default_str();
  cmd->add_option("--test-views", options->test_views, "Test views (orbit at 40 degrees)")->capture_default_str();
  cmd->add_option("--scales", options->scales, "Scales of OUT/multiscale (1 = none; the paper: 4)")
      ->capture_default_str();
  cmd->add_option("--seed", options->seed, "Seed of camera placement and jitter")->capture_default_str();
  cmd->add_option("--samples", options->samples_per_axis, "Jittered rays per pixel per axis (8: 64 rays per pixel)")
      ->capture_default_str();
  cmd->add_option("--threads", options->threads, "Render threads (0: all hardware threads)")->capture_default_str();
  auto lens = std::make_shared<std::string>();
  auto fov = std::make_shared<double>(0.0);
  cmd->add_option("--lens", *lens,
                  "Render through a lens, MODEL:c1,c2,... in COLMAP's order: " + lens_shapes() +
                      " (needs --scales 1; with --forward-facing the capture is written as a transforms.json)");
  cmd->add_option("--fov", *fov, "Horizontal field of view of the focal length, degrees (default: the Blender scenes' 39.6)");
  auto forward = std::make_shared<data::ForwardFacingOptions>();
  auto forward_facing = std::make_shared<bool>(false);
  auto grid = std::make_shared<std::string>("5x4");
  cmd->add_flag("--forward-facing", *forward_facing,
                "Instead: a forward-facing capture of the scene before a backdrop, from a grid of cameras, in the LLFF "
                "layout (poses_bounds.npy, images/, images_<factor>/); --size is then the image width (4:3), "
                "default 256");
  cmd->add_option("--grid", *grid, "--forward-facing: cameras across x down (e.g. 5x4)")->capture_default_str();
  cmd->add_option("--grid-width", forward->grid_width,
                  "--forward-facing: the camera grid's width in scene units (height: half), 4 from the scene; "
                  "narrower: less parallax")
      ->capture_default_str();
  cmd->add_option("--factor", forward->factor,
                  "--forward-facing, --unbounded: also write images_<factor>/ (1: none)")
      ->capture_default_str();
  cmd->add_flag("--jpeg", forward->jpeg,
                "--forward-facing, --unbounded: write the images as JPEG, as a phone capture holds them");
  auto unbounded = std::make_shared<bool>(false);
  cmd->add_flag("--unbounded", *unbounded,
                "Instead: a 360-degree capture of the scene outdoors (an endless ground, distant pillars, a sky), from "
                "a full orbit of cameras (--views, default 40), in the LLFF layout; --size is the image width (4:3), "
                "default 256");
  auto texture = std::make_shared<std::string>("checker");
  cmd->add_option("--texture", *texture,
                  "--unbounded: the surfaces: checker (checkers and stripes) or noise (the same colours under "
                  "non-periodic noise, which COLMAP can match: photos for `dataset from-photos`)")
      ->check(CLI::IsMember({"checker", "noise"}))
      ->capture_default_str();
  cmd->callback([out, options, forward, forward_facing, unbounded, grid, cmd, lens, fov, texture] {
    if (!lens->empty()) options->lens = parse_lens(*lens);
    if (cmd->count("--fov") > 0) {
      if (!(*fov > 0.0 && *fov < 170.0)) throw Error("--fov must be between 0 and 170 degrees");
      options->camera_angle_x = *fov * M_PI / 180.0;
    }
    if (!*unbounded && cmd->count("--texture") > 0) throw Error("--texture applies to --unbounded");
    if (*unbounded) {
      if (*forward_facing) throw Error("--unbounded and --forward-facing are two different scenes: give one");
      for (const char* blender_only : {"--val-views", "--test-views", "--scales", "--lens", "--grid", "--grid-width"}) {
        if (cmd->count(blender_only) > 0) throw Error(std::string(blender_only) + " does not apply to --unbounded");
      }
      data::UnboundedOptions scene;
      if (cmd->count("--size") > 0) scene.width_px = options->size_px;
      if (cmd->count("--views") > 0) scene.views = options->train_views;
      if (cmd->count("--samples") > 0) scene.samples_per_axis = options->samples_per_axis;
      if (cmd->count("--fov") > 0) scene.camera_angle_x = options->camera_angle_x;
      scene.factor = forward->factor;
      scene.jpeg = forward->jpeg;
      scene.seed = options->seed;
      scene.threads = options->threads;
      scene.texture = *texture == "noise" ? data::UnboundedTexture::noise : data::UnboundedTexture::checker;
      data::write_unbounded_scene(*out, scene, print_log);
      std::cout << "wrote " << *out << ": a 360-degree LLFF capture of " << scene.views << " views at "
                << scene.width_px << "x" << scene.width_px * 3 / 4 << " (images/"
                << (scene.factor > 1 ? ", images_" + std::to_string(scene.factor) + "/" : "") << ", poses_bounds.npy"
                << (scene.jpeg ? "; JPEG" : "") << ")\n";
      return;
    }
    if (*forward_facing) {
      for (const char* blender_only : {"--views", "--val-views", "--test-views", "--scales", "--fov"}) {
        if (cmd->count(blender_only) > 0) throw Error(std::string(blender_only) + " applies to the Blender scene, not --forward-facing");
      }
      unsigned x = 0, y = 0;
      char rest = 0;
      if (std::sscanf(grid->c_str(), "%ux%u%c", &x, &y, &rest) != 2) throw Error("--grid '" + *grid + "': expected COLUMNSxROWS, e.g. 5x4");
      forward->views_x = x;
      forward->views_y = y;
      if (cmd->count("--size") > 0) forward->width_px = options->size_px;
      forward->seed = options->seed;
      if (cmd->count("--samples") > 0) forward->samples_per_axis = options->samples_per_axis;
      forward->threads = options->threads;
      forward->lens = options->lens;
      if (!forward->lens.is_pinhole() && cmd->count("--factor") > 0 && forward->factor > 1) {
        throw Error("--factor writes images_<factor>/ of an LLFF capture; behind a --lens the capture is a "
                    "transforms.json, which train downsamples on load: give train --set factor=" +
                    std::to_string(forward->factor) + " instead");
      }
      data::write_forward_facing_scene(*out, *forward, print_log);
      const bool lens = !forward->lens.is_pinhole();
      std::cout << "wrote " << *out << ": " << (lens ? "a transforms.json" : "an LLFF capture") << " of " << x * y
                << (lens ? " forward-facing" : "") << " views at " << forward->width_px << "x" << forward->width_px * 3 / 4
                << (lens ? std::string(" behind an ") + lens_model_name(forward->lens.model) + " lens" : "") << " (images/"
                << (forward->factor > 1 && !lens ? ", images_" + std::to_string(forward->factor) + "/" : "")
                << (lens ? ", transforms.json" : ", poses_bounds.npy") << (forward->jpeg ? "; JPEG" : "") << ")\n";
      return;
    }
    for (const char* forward_only : {"--grid", "--grid-width", "--factor", "--jpeg"}) {
      if (cmd->count(forward_only) > 0) {
        throw Error(std::string(forward_only) + " applies to --forward-facing" +
                    (std::string(forward_only) == "--factor" || std::string(forward_only) == "--jpeg" ? " and --unbounded"
                                                                                                       : ""));
      }
    }
    data::write_procedural_scene(*out, *options, print_log);
    std::cout << "wrote " << *out << ": " << options->train_views << " train, " << options->val_views << " val, "
              << options->test_views << " test views at " << options->size_px << "x" << options->size_px;
    if (options->scales > 1) std::cout << "; multiscale (" << options->scales << " scales) in " << *out << "/multiscale";
    std::cout << "\n";
  });
}

}  // namespace mipnerf::cli
