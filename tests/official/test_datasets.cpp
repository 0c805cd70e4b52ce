// Our loaders (host/data: Blender, LLFF) and camera rays (kernels/rays.cl through ops::Rays) against the official
// datasets.py's own outputs (tests/official/fixtures, written by make_vectors.py from google/mipnerf): the files the
// official loader read are written again here from the fixture, loaded through our loader, and every camera, pixel
// and ray compared. Also: changing a convention (pixel centres at the corner, NDC near plane at 0 or 2) must NOT
// match the fixtures, so they would catch it.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "data/dataset.hpp"
#include "data/formats/llff_capture.hpp"
#include "io/json.hpp"
#include "io/npy.hpp"
#include "io/png.hpp"
#include "official_fixtures.hpp"
#include "official_scenes.hpp"
#include "ops/ray_bundle.hpp"
#include "ops/rays.hpp"
#include "support/data_fixtures.hpp"
#include "support/test_context.hpp"
#include "train/model.hpp"
#include "train/scene_effects.hpp"

using namespace mipnerf;
using official::flat;
using official::kU;
using official::norm1_at;
using official::norm2_at;
using official::run_rays;

namespace {

// The camera-to-world matrices of `cameras` (or `poses`), [C][3][4] flat.
std::vector<double> poses_of(const std::vector<Camera>& cameras) {
  std::vector<double> out;
  for (const auto& c : cameras) out.insert(out.end(), c.camera_to_world.begin(), c.camera_to_world.end());
  return out;
}

// Elements [C][h][w] (per pixel) of `values` whose pixel is (or is not) in the last row or last column: where the
// official radius takes its neighbour difference from the second-to-last pair (datasets.py pads the differences with
// d[:, -2:-1], the difference of rows h − 3 and h − 2, for row h − 1; columns alike).
template <typename T>
std::vector<T> pixels_at_edge(const std::vector<T>& values, size_t h, size_t w, bool edge) {
  std::vector<T> out;
  for (size_t i = 0; i < values.size(); ++i) {
    const size_t x = i % w, y = (i / w) % h;
    if ((x + 1 == w || y + 1 == h) == edge) out.push_back(values[i]);
  }
  return out;
}

// ---- Blender ----

// The official scene written again: transforms_train.json and train/r_<k>.png, byte for byte the same images.
void write_blender_scene(const io::Json& inputs, const std::string& dir) {
  const uint32_t w = inputs.at("width").get<uint32_t>(), h = inputs.at("height").get<uint32_t>();
  std::filesystem::create_directories(dir + "/train");
  const auto& frames = inputs.at("frames");
  for (size_t k = 0; k < frames.size(); ++k) {
    const auto rgba = flat(inputs.at("rgba8").at(k), {h, w, 4});
    const std::vector<uint8_t> bytes(rgba.begin(), rgba.end());
    io::write_png8(dir + "/train/r_" + std::to_string(k) + ".png", w, h, 4, bytes.data());
  }
  io::write_json(dir + "/transforms_train.json", {{"camera_angle_x", inputs.at("camera_angle_x")}, {"frames", frames}});
}

struct BlenderCase {
  io::Json fx;
  data::Dataset dataset;
};

BlenderCase load_blender_case(const test::TempDir& dir) {
  BlenderCase c{official::fixture("blender_rays.json"), {}};
  write_blender_scene(c.fx.at("inputs"), dir.path());
  data::LoadOptions options;
  options.splits = {"train"};
  options.background = Background::white;  // the official white_bkgd
  c.dataset = data::load_dataset(dir.path(), options);
  return c;
}

// Both sides compute a world direction in float32 from the same float32 pose: each component is a few roundings of
// terms bounded by the camera-frame direction's size, ≤ 8u·‖d‖₁ per side: 16u·‖d‖₁.
std::function<double(size_t)> direction_bound(const std::vector<double>& d) {
  return [&d](size_t i) { return 16 * kU * norm1_at(d, i); };
}

// ---- NDC and LLFF ----

// Our NDC rays and the official float64 ones: o_ndc = −(2f/w)·o_near.x/n, d_ndc = −(2f/w)·(d.x/d.z − o_near.x/n):
// each a handful of float32 operations on terms bounded by |o_ndc| + |d_ndc| and by (2f/w)·(|o| + 1) (the shifted
// origin o + t·d, t ≈ 1): 32u of their sum, per component (z: o_ndc.z = −1 and d_ndc.z = 2n/n are exact).
std::function<double(size_t)> ndc_bound(const std::vector<double>& origins, const std::vector<double>& dirs,
                                        double scale, double world_extent) {
  return [&origins, &dirs, scale, world_extent](size_t i) {
    return 32 * kU * (std::abs(origins[i]) + std::abs(dirs[i]) + scale * (world_extent + 1));
  };
}

Camera ndc_camera(const std::vector<double>& c2w, size_t c, double focal, uint32_t w, uint32_t h) {
  Camera camera;
  std::copy(c2w.begin() + 12 * c, c2w.begin() + 12 * (c + 1), camera.camera_to_world.begin());
  camera.focal_x_px = camera.focal_y_px = focal;
  camera.width_px = w;
  camera.height_px = h;
  camera.center_x_px = 0.5 * w;
  camera.center_y_px = 0.5 * h;
  camera.near = 0.0;
  camera.far = 1.0;
  return camera;
}

struct NdcCase {
  std::vector<Camera> cameras;
  std::vector<double> origins, directions, radii;
  double scale = 0, world_extent = 0;
  size_t h = 0, w = 0;
};

NdcCase load_ndc_case() {
  const auto fx = official::fixture("ndc.json");
  const auto& in = fx.at("inputs");
  const uint32_t w = in.at("width").get<uint32_t>(), h = in.at("height").get<uint32_t>();
  const double focal = in.at("focal").get<double>();
  REQUIRE(in.at("ndc_near_plane").get<double>() == 1.0);
  const size_t C = in.at("camtoworlds").size();
  const auto c2w = flat(in.at("camtoworlds"), {C, 3, 4});
  NdcCase c;
  for (size_t k = 0; k < C; ++k) {
    c.cameras.push_back(ndc_camera(c2w, k, focal, w, h));
    for (int r = 0; r < 3; ++r) c.world_extent = std::max(c.world_extent, std::abs(c2w[12 * k + 4 * r + 3]));
  }
  const auto& out = fx.at("outputs");
  c.origins = flat(out.at("origins"), {C, h, w, 3});
  c.directions = flat(out.at("directions"), {C, h, w, 3});
  c.radii = flat(out.at("radii"), {C, h, w});
  c.scale = 2 * focal / std::min(w, h);
  c.h = h;
  c.w = w;
  return c;
}

// The official LLFF capture written again (poses_bounds.npy as float64, images/view_<k>.png) into `dir`.
void write_llff_capture(const io::Json& inputs, const std::string& dir, size_t& height, size_t& width) {
  const size_t n = inputs.at("poses_bounds").size();
  io::write_npy(dir + "/poses_bounds.npy", flat(inputs.at("poses_bounds"), {n, 17}), {n, 17});
  std::filesystem::create_directories(dir + "/images");
  height = inputs.at("rgb8").at(0).size();
  width = inputs.at("rgb8").at(0).at(0).size();
  for (size_t k = 0; k < n; ++k) {
    const auto rgb = flat(inputs.at("rgb8").at(k), {height, width, 3});
    const std::vector<uint8_t> bytes(rgb.begin(), rgb.end());
    io::write_png8(dir + "/images/" + inputs.at("image_names").at(k).get<std::string>(), static_cast<uint32_t>(width),
                   static_cast<uint32_t>(height), 3, bytes.data());
  }
}

// The ray options `train` compiles for the capture in `dir`: the LLFF row's scene effects over the paper's defaults.
RaysOptions rays_options_train_chooses(const std::string& dir) {
  std::string line;
  const auto settings = train::with_scene_effects(train::scene_effects(dir, 1), {}, line);
  return train::make_graph_spec(train::resolve_config("paper", "mipnerf", settings), false).rays;
}

struct LlffCase {
  io::Json outputs;
  data::LlffCapture capture;
  data::Dataset dataset;
  data::LoadOptions options;
  size_t height = 0, width = 0;
};

LlffCase load_llff_case(const test::TempDir& dir, const std::string& which) {
  const auto fx = official::fixture("llff.json");
  LlffCase c;
  c.outputs = fx.at(which).at("outputs");
  write_llff_capture(fx.at(which).at("inputs"), dir.path(), c.height, c.width);
  c.options.llff.spherify = which == "spherify";
  c.options.holdout_every = 8;  // the official llffhold
  c.capture = data::read_llff(dir.path(), c.options);
  c.dataset = data::load_dataset(dir.path(), c.options);
  return c;
}

// A pose's float32 rounding on the official side (its loader casts the poses to float32 before rescaling and
// recentring, a product of a few float32-rounded matrices): 64u of max(1, |value|) per element.
std::function<double(size_t)> pose_bound(const std::vector<double>& poses, double ulps = 64) {
  return [&poses, ulps](size_t i) { return ulps * kU * std::max(1.0, std::abs(poses[i])); };
}

// Our loader's poses of the views `indices` (all views of the capture, before any split).
std::vector<double> capture_poses(const data::LlffCapture& capture, const io::Json& indices) {
  std::vector<double> out;
  for (const auto& i : indices) {
    const auto& p = capture.camera_to_world.at(i.get<size_t>());
    out.insert(out.end(), p.begin(), p.end());
  }
  return out;
}

void check_llff_poses_and_split(const LlffCase& c) {
  const auto& out = c.outputs;
  const size_t n_train = out.at("train_indices").size(), n_test = out.at("test_indices").size();
  const size_t n = n_train + n_test;
  REQUIRE(c.capture.camera_to_world.size() == n);
  CHECK(c.capture.focal_px == doctest::Approx(out.at("focal").get<double>()).epsilon(1e-12));
  CHECK(c.capture.height_px == out.at("height").get<uint32_t>());
  CHECK(c.capture.width_px == out.at("width").get<uint32_t>());

  // Bounds: the official rescales float32 bounds in float32 (2 roundings; spherify: 2 more): 8u relative.
  const auto bounds = flat(out.at("bounds"), {n, 2});
  std::vector<double> our_bounds;
  for (const auto& b : c.capture.bounds) our_bounds.insert(our_bounds.end(), b.begin(), b.end());
  OFFICIAL_CHECK_AGREES("rescaled bounds", our_bounds, bounds, [&](size_t i) { return 8 * kU * bounds[i]; });

  for (const std::string split : {"train", "test"}) {
    CAPTURE(split);
    const size_t count = split == "train" ? n_train : n_test;
    const auto poses = flat(out.at(split).at("camtoworlds"), {count, 3, 4});
    // The capture's views at the official split's indices, and our split's cameras (every 8th view held out).
    OFFICIAL_CHECK_AGREES("capture poses at the official " + split + " indices",
                          capture_poses(c.capture, out.at(split + "_indices")), poses, pose_bound(poses));
    const auto& ours = c.dataset.split(split);
    REQUIRE(ours.num_images() == count);
    OFFICIAL_CHECK_AGREES(split + " split camera poses", poses_of(ours.cameras), poses, pose_bound(poses));
    for (const auto& camera : ours.cameras) {
      CHECK(camera.focal_x_px == doctest::Approx(out.at("focal").get<double>()).epsilon(1e-12));
      CHECK(camera.width_px == c.width);
      CHECK(camera.height_px == c.height);
    }
    // Pixels: 8-bit codes / 255 on both sides.
    const auto images = flat(out.at(split).at("images"), {count, c.height, c.width, 3});
    OFFICIAL_CHECK_AGREES(split + " pixels", ours.rgb, images, official::constant_bound(2 * kU));
  }
}

}  // namespace

TEST_CASE("Blender rays: our loader and ray kernel give the official pixels, origins, directions and radii") {
  test::TempDir dir;
  const auto c = load_blender_case(dir);
  const auto& out = c.fx.at("outputs");
  const auto& split = c.dataset.split("train");
  const size_t C = split.num_images();
  const size_t h = c.fx.at("inputs").at("height").get<size_t>(), w = c.fx.at("inputs").at("width").get<size_t>();
  REQUIRE(C == c.fx.at("inputs").at("frames").size());
  for (const auto& camera : split.cameras) {
    CHECK(camera.focal_x_px == doctest::Approx(out.at("focal").get<double>()).epsilon(1e-12));
    CHECK(camera.near == out.at("near").get<double>());
    CHECK(camera.far == out.at("far").get<double>());
  }
  // Pixels: straight RGBA over white, v/255·a/255 + (1 − a/255) in float32 on both sides: a few roundings of ≤ 1.
  OFFICIAL_CHECK_AGREES("pixels (white background)", split.rgb, flat(out.at("pixels"), {C, h, w, 3}),
                        official::constant_bound(4 * kU));

  const auto rays = run_rays(split.cameras, RaysOptions{});
  const auto origins = flat(out.at("origins"), {C, h, w, 3}), dirs = flat(out.at("directions"), {C, h, w, 3});
  const auto viewdirs = flat(out.at("viewdirs"), {C, h, w, 3}), radii = flat(out.at("radii"), {C, h, w});
  // Origins: the pose's float32 translation, copied on both sides.
  OFFICIAL_CHECK_AGREES("origins", rays.origins, origins, official::constant_bound(0.0));
  OFFICIAL_CHECK_AGREES("directions", rays.directions, dirs, direction_bound(dirs));
  // Unit view directions: the directions' 16u·‖d‖₁/‖d‖ relative, and a normalisation (4u) per side.
  OFFICIAL_CHECK_AGREES("viewdirs", rays.viewdirs, viewdirs,
                        [&](size_t i) { return 16 * kU * norm1_at(dirs, i) / norm2_at(dirs, i) + 8 * kU; });
  // Radii: the official differences neighbouring float32 directions (‖d‖ ≈ 1, their difference ≈ 1/f), so its
  // relative error is ~4u·‖d‖·f; ours is |R column|/f·2/√12 (4u): 8u·(1 + ‖d‖·f) relative.
  const double focal = out.at("focal").get<double>();
  OFFICIAL_CHECK_AGREES("radii", rays.radii, radii,
                        [&](size_t i) { return 8 * kU * (1 + norm2_at(dirs, 3 * i) * focal) * radii[i]; });
}

TEST_CASE("Blender rays: pixel rays through the corner (pixel_center 0, original NeRF) do not match the official") {
  test::TempDir dir;
  const auto c = load_blender_case(dir);
  const auto& out = c.fx.at("outputs");
  const auto& split = c.dataset.split("train");
  const size_t h = c.fx.at("inputs").at("height").get<size_t>(), w = c.fx.at("inputs").at("width").get<size_t>();
  RaysOptions corner;
  corner.pixel_center_offset = 0.0f;
  const auto rays = run_rays(split.cameras, corner);
  const auto dirs = flat(out.at("directions"), {split.num_images(), h, w, 3});
  // Half a pixel is 0.5/f ≈ 0.05 of a direction: ~10^4 times the bound; 100 is a clear margin.
  OFFICIAL_CHECK_DISAGREES("directions with pixel_center 0", rays.directions, dirs, 100.0, direction_bound(dirs));
}

TEST_CASE("NDC rays: our cylinder rays are the official convert_to_ndc rays (near plane 1) and NDC radii") {
  const auto c = load_ndc_case();
  RaysOptions options;
  options.ray_shape = RayShape::cylinder;
  const auto rays = run_rays(c.cameras, options);
  OFFICIAL_CHECK_AGREES("NDC origins", rays.origins, c.origins,
                        ndc_bound(c.origins, c.directions, c.scale, c.world_extent));
  OFFICIAL_CHECK_AGREES("NDC directions", rays.directions, c.directions,
                        ndc_bound(c.origins, c.directions, c.scale, c.world_extent));
  // The official radius differences neighbouring NDC origins (in float64 here); ours is the difference written
  // without cancellation, a dozen float32 operations: 64u relative. Pixels off the last row and column here; those
  // have their own test case below.
  const auto theirs = pixels_at_edge(c.radii, c.h, c.w, false);
  OFFICIAL_CHECK_AGREES("NDC radii off the last row and column", pixels_at_edge(rays.radii, c.h, c.w, false), theirs,
                        [&](size_t i) { return 64 * kU * theirs[i]; });
}

TEST_CASE("NDC rays: a near plane at 0 or 2 instead of the official 1 does not match the official") {
  const auto c = load_ndc_case();
  for (const float near_plane : {0.0f, 2.0f}) {
    CAPTURE(near_plane);
    RaysOptions options;
    options.ray_shape = RayShape::cylinder;
    options.ndc_near_plane = near_plane;
    const auto rays = run_rays(c.cameras, options);
    // Near plane 0 divides by zero (not finite: infinitely far off); 2 moves the NDC origins by O(0.1).
    OFFICIAL_CHECK_DISAGREES("NDC origins", rays.origins, c.origins, 100.0,
                             ndc_bound(c.origins, c.directions, c.scale, c.world_extent));
  }
}

TEST_CASE("LLFF loader: our poses, bounds, split and pixels are the official forward-facing capture's") {
  test::TempDir dir;
  const auto c = load_llff_case(dir, "forward_facing");
  CHECK_FALSE(c.capture.spherify);
  check_llff_poses_and_split(c);
}

TEST_CASE("LLFF loader: our spiral render path is the official one, 120 views") {
  test::TempDir dir;
  const auto c = load_llff_case(dir, "forward_facing");
  const auto expected = flat(c.outputs.at("test").at("render_poses"), {120, 3, 4});
  const auto path = data::llff_render_path(c.capture, c.options, 120);
  // The spiral is float64 on both sides from float32-rounded poses (the official cast): the poses' 64u, carried through
  // an average, a percentile, two normalisations and a look-at: 256u of max(1, |value|).
  OFFICIAL_CHECK_AGREES("spiral render poses", poses_of(path), expected, pose_bound(expected, 256));
}

TEST_CASE("LLFF rays: our NDC rays of the held-out views are the official ones") {
  test::TempDir dir;
  const auto c = load_llff_case(dir, "forward_facing");
  const auto& test_split = c.dataset.split("test");
  const size_t C = test_split.num_images(), h = c.height, w = c.width;
  for (const auto& camera : test_split.cameras) {
    CHECK(camera.near == 0.0);
    CHECK(camera.far == 1.0);
  }
  RaysOptions options;
  options.ray_shape = RayShape::cylinder;
  const auto rays = run_rays(test_split.cameras, options);
  const auto& official_rays = c.outputs.at("test").at("rays");
  const auto origins = flat(official_rays.at("origins"), {C, h, w, 3});
  const auto dirs = flat(official_rays.at("directions"), {C, h, w, 3});
  const auto radii = flat(official_rays.at("radii"), {C, h, w});
  double extent = 0;
  for (const auto& camera : test_split.cameras) {
    for (int r = 0; r < 3; ++r) extent = std::max(extent, std::abs(camera.camera_to_world[4 * r + 3]));
  }
  const double scale = 2 * c.capture.focal_px / static_cast<double>(std::min(w, h));
  // Both sides in float32 here (the official loader's arrays are float32) and our pose differs from its by the
  // pose bound: twice the NDC bound.
  const auto bound = ndc_bound(origins, dirs, scale, extent);
  OFFICIAL_CHECK_AGREES("LLFF NDC origins", rays.origins, origins, [&](size_t i) { return 2 * bound(i); });
  OFFICIAL_CHECK_AGREES("LLFF NDC directions", rays.directions, dirs, [&](size_t i) { return 2 * bound(i); });
  // The official radius differences float32 NDC origins (≈ 1) of neighbours ≈ 2/w apart: ~4u·w/2 relative on its
  // side; 64u on ours. Pixels off the last row and column (those: the test case below).
  const auto theirs = pixels_at_edge(radii, h, w, false);
  OFFICIAL_CHECK_AGREES("LLFF NDC radii off the last row and column", pixels_at_edge(rays.radii, h, w, false), theirs,
                        [&](size_t i) { return (64 + 2.0 * static_cast<double>(w)) * kU * theirs[i]; });
}

// The official pads the neighbour differences of the last row (column) with the second-to-last difference
// (datasets.py, LLFF._generate_rays: `dx = np.concatenate([dx, dx[:, -2:-1, :]], 1)`, the pair of rows h − 3 and
// h − 2), where ours takes the last pair (h − 2, h − 1). World-ray radii do not notice (pinhole directions differ by
// the same vector everywhere); NDC origins are not evenly spaced, so the last row's and column's radii differ.
TEST_CASE("NDC radii: the last pixel row and column have the official radii") {
  SUBCASE("ndc.json (float64 official)") {
    const auto c = load_ndc_case();
    RaysOptions options;
    options.ray_shape = RayShape::cylinder;
    const auto rays = run_rays(c.cameras, options);
    const auto theirs = pixels_at_edge(c.radii, c.h, c.w, true);
    // As for the other pixels: 64u relative.
    OFFICIAL_CHECK_AGREES("NDC radii of the last row and column", pixels_at_edge(rays.radii, c.h, c.w, true), theirs,
                          [&](size_t i) { return 64 * kU * theirs[i]; });
  }
  SUBCASE("llff.json (the official loader, float32)") {
    test::TempDir dir;
    const auto c = load_llff_case(dir, "forward_facing");
    const auto& test_split = c.dataset.split("test");
    RaysOptions options;
    options.ray_shape = RayShape::cylinder;
    const auto rays = run_rays(test_split.cameras, options);
    const auto radii = flat(c.outputs.at("test").at("rays").at("radii"), {test_split.num_images(), c.height, c.width});
    const auto theirs = pixels_at_edge(radii, c.height, c.width, true);
    OFFICIAL_CHECK_AGREES("LLFF NDC radii of the last row and column",
                          pixels_at_edge(rays.radii, c.height, c.width, true), theirs,
                          [&](size_t i) { return (64 + 2.0 * static_cast<double>(c.width)) * kU * theirs[i]; });
  }
}

// The official LLFF loader passes the un-normalised world directions as viewdirs (datasets.py, LLFF._generate_rays:
// viewdirs=self.rays.directions, taken before the NDC conversion). Ours follow it with the ray options `train` chooses
// for the capture (the LLFF row's scene effects: cylinders, unit_viewdirs = false).
TEST_CASE("LLFF rays: our view directions of the held-out views are the official ones (un-normalised)") {
  test::TempDir dir;
  const auto c = load_llff_case(dir, "forward_facing");
  const auto& test_split = c.dataset.split("test");
  const RaysOptions options = rays_options_train_chooses(dir.path());
  CHECK(options.ray_shape == RayShape::cylinder);
  CHECK_FALSE(options.unit_viewdirs);
  const auto rays = run_rays(test_split.cameras, options);
  const auto viewdirs =
      flat(c.outputs.at("test").at("rays").at("viewdirs"), {test_split.num_images(), c.height, c.width, 3});
  // World directions in float32 on both sides from poses within the pose bound: 16u·‖d‖₁ + the pose's 64u·‖d‖₁.
  OFFICIAL_CHECK_AGREES("LLFF viewdirs", rays.viewdirs, viewdirs,
                        [&](size_t i) { return 80 * kU * norm1_at(viewdirs, i); });
}

TEST_CASE("LLFF loader with spherify: our poses, bounds, split and pixels are the official 360-degree capture's") {
  test::TempDir dir;
  const auto c = load_llff_case(dir, "spherify");
  CHECK(c.capture.spherify);
  check_llff_poses_and_split(c);
}

TEST_CASE("LLFF loader with spherify: our world rays of the held-out views are the official ones") {
  test::TempDir dir;
  const auto c = load_llff_case(dir, "spherify");
  const auto& test_split = c.dataset.split("test");
  const size_t C = test_split.num_images(), h = c.height, w = c.width;
  // The options train chooses for a 360° capture: world rays, cones and unit view directions (the official spherified
  // capture goes through the Blender ray generation, which normalises them).
  const RaysOptions options = rays_options_train_chooses(dir.path());
  CHECK(options.ray_shape == RayShape::cone);
  CHECK(options.unit_viewdirs);
  const auto rays = run_rays(test_split.cameras, options);
  const auto& official_rays = c.outputs.at("test").at("rays");
  const auto origins = flat(official_rays.at("origins"), {C, h, w, 3});
  const auto dirs = flat(official_rays.at("directions"), {C, h, w, 3});
  const auto viewdirs = flat(official_rays.at("viewdirs"), {C, h, w, 3});
  const auto radii = flat(official_rays.at("radii"), {C, h, w});
  // Origins are the poses' translations (pose bound); directions and view directions the Blender bounds plus the
  // pose bound's 64u·‖d‖₁; radii as for Blender, plus the pose's 64u.
  OFFICIAL_CHECK_AGREES("spherified origins", rays.origins, origins, pose_bound(origins));
  OFFICIAL_CHECK_AGREES("spherified directions", rays.directions, dirs,
                        [&](size_t i) { return 80 * kU * norm1_at(dirs, i); });
  OFFICIAL_CHECK_AGREES("spherified viewdirs", rays.viewdirs, viewdirs,
                        [&](size_t i) { return 80 * kU * norm1_at(dirs, i) / norm2_at(dirs, i) + 8 * kU; });
  const double focal = c.capture.focal_px;
  OFFICIAL_CHECK_AGREES("spherified radii", rays.radii, radii,
                        [&](size_t i) { return (72 + 8 * norm2_at(dirs, 3 * i) * focal) * kU * radii[i]; });
}

TEST_CASE("LLFF loader with spherify: our circular render path is the official one, 120 views") {
  test::TempDir dir;
  const auto c = load_llff_case(dir, "spherify");
  const auto expected = flat(c.outputs.at("test").at("render_poses"), {120, 3, 4});
  const auto path = data::llff_render_path(c.capture, c.options, 120);
  // As the spiral: float64 from float32-rounded poses, through the spherify solve: 256u of max(1, |value|).
  OFFICIAL_CHECK_AGREES("spherical render poses", poses_of(path), expected, pose_bound(expected, 256));
}
