// LLFF captures (data/formats/llff_capture.hpp, io/npy.hpp) on the forward-facing built-in scene (data/synthetic/forward_facing.hpp): the
// official transformations against the cameras that rendered it, splits, factors, NDC or world bounds, the render
// path, the .npy reader's errors, and malformed captures as one line each.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "data/dataset.hpp"
#include "data/synthetic/forward_facing.hpp"
#include "data/synthetic/unbounded.hpp"
#include "data/formats/llff_capture.hpp"
#include "data/formats/formats.hpp"
#include "io/npy.hpp"
#include "support/jpeg_writer.hpp"
#include "support/temp_scene.hpp"
#include "train/scene_effects.hpp"

using namespace mipnerf;
namespace fs = std::filesystem;

namespace {

data::ForwardFacingOptions small_capture() {
  data::ForwardFacingOptions options;
  options.width_px = 64;  // images/ 64x48, images_4/ 16x12
  options.samples_per_axis = 1;
  options.threads = 2;
  return options;
}

// The capture written once per test process.
const std::string& capture_dir() {
  static const std::string dir = [] {
    const auto path = test::fresh_temp_dir("llff");
    data::write_forward_facing_scene(path.string(), small_capture());
    return path.string();
  }();
  return dir;
}

// A copy of the capture to damage.
fs::path copy_of_capture(const std::string& name) {
  const auto dir = test::fresh_temp_dir(name);
  fs::copy(capture_dir(), dir, fs::copy_options::recursive);
  return dir;
}

using data::Matrix34;
// (R_aᵀ R_b)[r][c]: b's rotation seen from camera a, which a rigid motion of the world leaves unchanged.
double rotation_product(const Matrix34& a, const Matrix34& b, int r, int c) {
  return a[r] * b[c] + a[4 + r] * b[4 + c] + a[8 + r] * b[8 + c];
}
double distance(const Matrix34& a, const Matrix34& b) { return std::hypot(a[3] - b[3], a[7] - b[7], a[11] - b[11]); }

}  // namespace

TEST_CASE("npy: float64 arrays round-trip, and malformed files are one line naming them") {
  const std::vector<double> values = {1.5, -2.0, 3.25, 1e300, -0.0, 7.0};
  const std::string bytes = io::npy_bytes(values, {2, 3});
  CHECK((bytes.size() - values.size() * 8) % 64 == 0);  // the data starts on a 64-byte boundary, as numpy's
  const io::NpyArray back = io::parse_npy(bytes, "a.npy");
  CHECK(back.shape == std::vector<size_t>{2, 3});
  CHECK(back.values == values);
  // float32 and a version-2 header (4-byte length), written by hand.
  std::string header = "{'shape': (2,), 'fortran_order': False, 'descr': '<f4'}";
  std::string v2 = std::string("\x93NUMPY\x02\x00", 8);
  for (int i = 0; i < 4; ++i) v2 += static_cast<char>((header.size() >> (8 * i)) & 0xff);
  v2 += header;
  const float f[2] = {0.5f, -4.0f};
  v2.append(reinterpret_cast<const char*>(f), sizeof(f));
  CHECK(io::parse_npy(v2, "b.npy").values == std::vector<double>{0.5, -4.0});

  auto with_header = [](const std::string& dict, size_t data_bytes) {
    std::string b = std::string("\x93NUMPY\x01\x00", 8);
    b += static_cast<char>(dict.size() & 0xff);
    b += static_cast<char>(dict.size() >> 8);
    return b + dict + std::string(data_bytes, '\0');
  };
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"PK\x03\x04 a zip file", "not a .npy file"},
      {with_header("{'descr': '<i4', 'fortran_order': False, 'shape': (2,), }", 8), "dtype '<i4'"},
      {with_header("{'descr': '>f8', 'fortran_order': False, 'shape': (2,), }", 16), "dtype '>f8'"},
      {with_header("{'descr': '<f8', 'fortran_order': True, 'shape': (2, 2), }", 32), "Fortran-order"},
      {with_header("{'descr': '<f8', 'fortran_order': False, 'shape': (3, 17), }", 8 * 60),
       "480 bytes of data where its shape needs 408"},
      {with_header("{'descr': '<f8', 'fortran_order': False, 'shape': (99999999999, 99999999999), }", 8),
       "needs more data"},
      {with_header("{'descr': '<f8', 'fortran_order': False, 'shape': (2,), 'extra': 1}", 16), "unknown key 'extra'"},
      {with_header("{'descr': '<f8', 'shape': (2,)}", 16), "needs the keys"},
      {with_header("{'descr': '<f8', 'fortran_order': False, 'shape': (2,", 16), "malformed .npy header"},
      {with_header("{'descr': '<f8', 'fortran_order': Maybe, 'shape': (2,)}", 16), "expected True or False"},
      {bytes.substr(0, 9), "truncated"},
      {std::string("\x93NUMPY\x07\x00", 8) + "xx", "version 7"},
  };
  for (const auto& [file, message] : bad) {
    CHECK_THROWS_WITH_AS(io::parse_npy(file, "bad.npy"), doctest::Contains(message.c_str()), Error);
  }
}

TEST_CASE("llff: the official transformations keep the capture's geometry, scaled so the nearest bound is 1/0.75") {
  const auto known = data::forward_facing_cameras(small_capture());
  data::LoadOptions options;
  options.factor = 4;
  const data::LlffCapture capture = data::read_llff(capture_dir(), options);
  REQUIRE(capture.camera_to_world.size() == known.size());
  CHECK(capture.stored_factor == 4);
  CHECK(capture.image_dir == (fs::path(capture_dir()) / "images_4").string());
  CHECK(capture.focal_px == doctest::Approx(known[0].focal_x_px / 4).epsilon(1e-12));
  double nearest = 1e300, known_nearest = 1e300;
  for (size_t i = 0; i < known.size(); ++i) {
    nearest = std::min(nearest, capture.bounds[i][0]);
    known_nearest = std::min(known_nearest, known[i].near);
  }
  CHECK(nearest == doctest::Approx(1.0 / 0.75).epsilon(1e-12));
  const double scale = 1.0 / (known_nearest * 0.75);
  // Recentred: the mean position is the origin, the summed viewing axes point along z.
  double mean[3] = {0, 0, 0}, axis[3] = {0, 0, 0};
  for (const auto& pose : capture.camera_to_world) {
    for (int r = 0; r < 3; ++r) {
      mean[r] += pose[4 * r + 3] / static_cast<double>(known.size());
      axis[r] += pose[4 * r + 2];
    }
  }
  for (double m : mean) CHECK(m == doctest::Approx(0.0).scale(1.0));
  CHECK(axis[0] == doctest::Approx(0.0).scale(1.0));
  CHECK(axis[1] == doctest::Approx(0.0).scale(1.0));
  CHECK(axis[2] > 0.99 * static_cast<double>(known.size()));
  // One rigid motion and one scale map the rendering cameras onto the loaded ones: relative rotations are equal,
  // distances between camera centres scale by 1 / (0.75 · nearest bound).
  for (size_t i = 0; i < known.size(); ++i) {
    for (size_t j = 0; j < known.size(); j += 7) {
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
          CHECK(rotation_product(capture.camera_to_world[i], capture.camera_to_world[j], r, c) ==
                doctest::Approx(rotation_product(known[i].camera_to_world, known[j].camera_to_world, r, c)).scale(1.0));
        }
      }
      CHECK(distance(capture.camera_to_world[i], capture.camera_to_world[j]) ==
            doctest::Approx(scale * distance(known[i].camera_to_world, known[j].camera_to_world)).scale(1.0));
    }
  }
  CHECK(!data::looks_360(capture));
}

TEST_CASE(
    "llff: every 8th view is held out as test (and val), NDC bounds, factors from images_<factor> or downsampled") {
  data::LoadOptions options;
  options.factor = 4;
  const data::Dataset dataset = data::load_dataset(capture_dir(), options);
  CHECK(dataset.format == data::DatasetFormat::llff);
  REQUIRE(dataset.has_split("train"));
  CHECK(dataset.split("train").num_images() == 17);
  CHECK(dataset.split("test").num_images() == 3);  // views 0, 8, 16
  CHECK(dataset.split("val").num_images() == 3);
  CHECK(dataset.split("test").files[1].find("image008.png") != std::string::npos);
  const Camera& camera = dataset.split("train").cameras[0];
  CHECK(camera.width_px == 16);
  CHECK(camera.height_px == 12);
  CHECK(camera.center_x_px == 8.0);
  CHECK(camera.near == 0.0);
  CHECK(camera.far == 1.0);

  // Factor 2 has no images_2/: images/ downsampled on load, with the focal length halved.
  options.factor = 2;
  const data::Dataset halved = data::load_dataset(capture_dir(), options);
  const data::LlffCapture full = data::read_llff(capture_dir(), data::LoadOptions{});
  CHECK(halved.split("train").cameras[0].width_px == 32);
  CHECK(halved.split("train").cameras[0].focal_x_px == doctest::Approx(full.focal_px / 2).epsilon(1e-12));

  // World rays (cones) instead of NDC: the rescaled bounds.
  options.llff.ndc = false;
  const data::Dataset world = data::load_dataset(capture_dir(), options);
  CHECK(world.split("train").cameras[0].near > 1.0);
  CHECK(world.split("train").cameras[0].far > world.split("train").cameras[0].near);
  options.holdout_every = 0;
  CHECK(!data::load_dataset(capture_dir(), options).has_split("test"));

  const auto traits = data::scene_traits(capture_dir(), data::LoadOptions{});
  CHECK(traits.format == data::DatasetFormat::llff);
  CHECK(!traits.all_around);
  CHECK(!traits.has_alpha);
}

TEST_CASE("llff: the spiral render path circles the capture's average view, looking forward") {
  data::LoadOptions options;
  options.factor = 4;
  const data::LlffCapture capture = data::read_llff(capture_dir(), options);
  const auto path = data::llff_render_path(capture, options, 12);
  REQUIRE(path.size() == 12);
  double largest = 0;
  for (const auto& pose : capture.camera_to_world) largest = std::max({largest, std::abs(pose[3]), std::abs(pose[7])});
  for (const Camera& camera : path) {
    CHECK(camera.width_px == 16);
    CHECK(camera.near == 0.0);
    CHECK(camera.camera_to_world[10] > 0.95);  // its z axis (backwards) close to the average's
    CHECK(std::abs(camera.camera_to_world[3]) <= largest * 1.01);
  }
  CHECK(path[0].camera_to_world[3] != doctest::Approx(path[3].camera_to_world[3]));
  CHECK_THROWS_WITH_AS(data::llff_render_path(capture, options, 0), doctest::Contains("at least one frame"), Error);
  // Every camera at the origin: the spherical path's circle has no radius and no axis to look along. It is refused
  // in one line, never returned as NaN cameras.
  data::LlffCapture collapsed = capture;
  collapsed.spherify = true;
  for (auto& pose : collapsed.camera_to_world) pose[3] = pose[7] = pose[11] = 0.0;
  CHECK_THROWS_WITH_AS(data::llff_render_path(collapsed, options, 4), doctest::Contains("no render path"), Error);
}

TEST_CASE("llff: a capture of JPEG photos loads like one of PNGs") {
  const auto dir = copy_of_capture("llff-jpeg");
  for (const auto& entry : fs::directory_iterator(dir / "images_4")) {
    const data::RgbaImage png = data::load_rgba_image(entry.path().string());
    std::vector<float> rgb;
    for (size_t p = 0; p < png.rgba.size() / 4; ++p)
      rgb.insert(rgb.end(), png.rgba.begin() + 4 * p, png.rgba.begin() + 4 * p + 3);
    test::write_jpeg((dir / "images_4" / entry.path().stem()).string() + ".JPG", png.width, png.height, rgb, 100);
    fs::remove(entry.path());
  }
  data::LoadOptions options;
  options.factor = 4;
  const data::Dataset photos = data::load_dataset(dir.string(), options);
  const data::Dataset pngs = data::load_dataset(capture_dir(), options);
  REQUIRE(photos.split("train").rgb.size() == pngs.split("train").rgb.size());
  double sum = 0;
  const auto& a = photos.split("train").rgb;
  const auto& b = pngs.split("train").rgb;
  for (size_t k = 0; k < a.size(); ++k) sum += std::abs(double(a[k]) - b[k]);
  // JPEG's loss only: quality 100, but 4:2:0 chroma on 16x12 images of sharp stripes moves single samples by up to
  // a third; on average a few levels.
  CHECK(sum / static_cast<double>(a.size()) < 0.03);
  CHECK(photos.split("train").cameras[0].focal_x_px == pngs.split("train").cameras[0].focal_x_px);
}

TEST_CASE("llff: a capture looking inward from all around is 360 degrees, spherified to unit mean distance") {
  const auto dir = copy_of_capture("llff-360");
  // The 20 images re-posed on a circle of radius 3 at height 1, each looking at the origin, in LLFF's columns.
  std::vector<double> rows;
  for (int k = 0; k < 20; ++k) {
    const double a = 2.0 * M_PI * k / 20.0;
    const data::Matrix34 m = data::look_at_pose({3 * std::cos(a), 3 * std::sin(a), 1.0}, {0, 0, 0}, {0, 0, 1});
    const double hwf[3] = {48, 64, 60};
    for (int r = 0; r < 3; ++r) {
      for (double value : {-m[4 * r + 1], m[4 * r + 0], m[4 * r + 2], m[4 * r + 3], hwf[r]}) rows.push_back(value);
    }
    rows.push_back(2.0);
    rows.push_back(4.5);
  }
  io::write_npy((dir / "poses_bounds.npy").string(), rows, {20, 17});
  const auto traits = data::scene_traits(dir.string(), data::LoadOptions{});
  CHECK(traits.all_around);
  const train::SceneEffects effects = train::scene_effects(dir.string(), 1);  // what train then chooses
  CHECK(effects.summary == "360° LLFF capture → spherified poses, world rays, cones, black background");
  CHECK(effects.settings.at("spherify") == "true");
  CHECK(effects.settings.at("ray_shape") == "cone");
  // Each family gets its own unbounded group, all of it or, where an explicit setting disagrees with one of them, none
  // (the line says which); NeRF none. mip-NeRF: mip-NeRF 360's model at the official degrees.
  CHECK(effects.zipnerf_settings.empty());
  CHECK(effects.mipnerf_settings.at("unbounded") == "true");
  CHECK(effects.mipnerf_settings.at("sampler") == "proposal");
  CHECK(effects.mipnerf_settings.at("pos_max_deg") == "12");
  const train::SceneEffects nerf = train::scene_effects(dir.string(), 1, train::ModelFamily::nerf);
  CHECK(nerf.zipnerf_settings.empty());
  CHECK(nerf.mipnerf_settings.empty());
  {
    std::string mip_line;
    auto mip_settings = train::with_scene_effects(effects, {}, mip_line);
    CHECK(mip_line.find("; mip-NeRF unbounded as mip-NeRF 360 (frustums contracted") != std::string::npos);
    const auto mip = train::resolve_config("paper", "mipnerf", mip_settings);  // the paper preset's degrees 0..15 too
    CHECK(mip.unbounded);
    CHECK(mip.sampler == train::Sampler::proposal);
    CHECK(mip.pos_max_deg == 12);
    mip_settings = train::with_scene_effects(effects, {{"pos_max_deg", "16"}}, mip_line);
    CHECK(mip_settings.count("unbounded") == 0);
    CHECK(mip_line.find("mip-NeRF not unbounded as mip-NeRF 360") != std::string::npos);
    CHECK(!train::resolve_config("quick", "mipnerf", mip_settings).unbounded);
  }
  CHECK(train::scene_effects(dir.string(), 1, train::ModelFamily::zipnerf).mipnerf_settings.empty());
  const train::SceneEffects zip = train::scene_effects(dir.string(), 1, train::ModelFamily::zipnerf);
  CHECK(zip.zipnerf_settings.at("unbounded") == "true");
  CHECK(zip.zipnerf_settings.at("sampler") == "proposal");
  std::string line;
  auto settings = train::with_scene_effects(zip, {}, line);
  CHECK(settings.at("unbounded") == "true");
  CHECK(settings.at("sampler") == "proposal");
  CHECK(line.find("; Zip-NeRF unbounded (contraction") != std::string::npos);
  CHECK(train::resolve_config("fast", "zipnerf", settings).unbounded);
  settings = train::with_scene_effects(zip, {{"sampler", "resample"}}, line);
  CHECK(settings.count("unbounded") == 0);
  CHECK(settings.at("sampler") == "resample");
  CHECK(line.find("Zip-NeRF not unbounded (contraction") != std::string::npos);
  CHECK(line.find("(given explicitly: sampler = resample)") != std::string::npos);
  CHECK(!train::resolve_config("fast", "zipnerf", settings).unbounded);  // and it resolves: nothing half-applied
  settings = train::with_scene_effects(zip, {{"unbounded", "false"}}, line);
  CHECK(settings.at("unbounded") == "false");
  CHECK(settings.count("sampler") == 0);
  data::LoadOptions options;
  options.llff.spherify = true;
  const data::LlffCapture capture = data::read_llff(dir.string(), options);
  double mean_square = 0;
  for (const auto& pose : capture.camera_to_world) {
    mean_square += (pose[3] * pose[3] + pose[7] * pose[7] + pose[11] * pose[11]) / 20.0;
  }
  CHECK(mean_square == doctest::Approx(1.0));
  // World rays between the rescaled bounds, not NDC.
  const data::Dataset dataset = data::load_dataset(dir.string(), options);
  CHECK(dataset.split("train").cameras[0].near > 0.0);
  CHECK(dataset.split("train").cameras[0].far != 1.0);
  const auto circle = data::llff_render_path(capture, options, 8);
  REQUIRE(circle.size() == 8);
  for (const Camera& camera : circle) {
    const double radius = std::hypot(camera.camera_to_world[3], camera.camera_to_world[7], camera.camera_to_world[11]);
    CHECK(radius == doctest::Approx(1.0).epsilon(0.05));
  }
}

// make-scene --unbounded: the procedural scene outdoors from a full orbit, in the LLFF layout. The loader and train
// take it for a 360° capture (spherified, world rays, cones) with no flag; every pixel is opaque (the ground and the sky
// fill what the scene does not); each view's bounds come from the finite depths it sees while the sky (t = +∞) and the
// far ground lie beyond them, as for a real capture outdoors; the forward-facing capture is unchanged by the shared
// writer (its bounds, checked in the test above, and its images below).
TEST_CASE("llff: the built-in unbounded scene is a 360-degree capture whose sky and far ground lie beyond its bounds") {
  const auto dir = test::fresh_temp_dir("llff-unbounded");
  data::UnboundedOptions options;
  options.width_px = 64;  // 64x48, images_4/ 16x12
  options.views = 16;
  options.samples_per_axis = 1;
  options.threads = 2;
  data::write_unbounded_scene(dir.string(), options);
  const auto traits = data::scene_traits(dir.string(), data::LoadOptions{});
  CHECK(traits.all_around);
  const train::SceneEffects effects = train::scene_effects(dir.string(), 1);
  CHECK(effects.settings.at("spherify") == "true");
  CHECK(effects.settings.at("ray_shape") == "cone");
  const auto cameras = data::unbounded_cameras(options);
  REQUIRE(cameras.size() == 16);
  size_t sky = 0, beyond_far = 0, rays = 0;
  for (const Camera& camera : cameras) {
    CHECK(camera.near > 1.0);  // the nearest surface, about 3 away (the scene within 1.5 of the centre, 4 out)
    CHECK(camera.far > camera.near);
    CHECK(std::isfinite(camera.far));
    for (int j = 0; j < 12; ++j) {
      for (int i = 0; i < 16; ++i) {
        const auto hit = data::trace_unbounded(camera_ray(camera, 4.0 * i + 2.0, 4.0 * j + 2.0));
        CHECK(hit.hit);
        ++rays;
        sky += !std::isfinite(hit.t);
        beyond_far += hit.t > camera.far;
      }
    }
  }
  CHECK(sky > rays / 20);          // the sky is seen (upper part of the views)
  CHECK(beyond_far > sky);         // and the far ground beyond the bounds too
  CHECK(beyond_far < rays / 2);    // while most of each view lies within them
  // Every view from outside the scene, all around it: azimuths cover the circle.
  double spread = 0;
  for (const Camera& a : cameras) {
    for (const Camera& b : cameras) {
      const double dot = a.camera_to_world[2] * b.camera_to_world[2] + a.camera_to_world[6] * b.camera_to_world[6] +
                         a.camera_to_world[10] * b.camera_to_world[10];
      spread = std::max(spread, std::acos(std::clamp(dot, -1.0, 1.0)));
    }
  }
  CHECK(spread > 0.9 * M_PI);
  // Opaque everywhere: every supersampled ray of a view hits something.
  data::SceneOptions render;
  render.samples_per_axis = 2;
  const auto image = data::render_traced(cameras[5], render, 0, data::trace_unbounded);
  for (size_t p = 0; p < image.rgba.size() / 4; ++p) REQUIRE(image.rgba[4 * p + 3] == 1.0f);
  CHECK(data::load_dataset(dir.string(), data::LoadOptions{}).split("train").num_images() == 14);  // every 8th held out
  CHECK(data::unbounded_cameras(options)[3].camera_to_world == cameras[3].camera_to_world);  // deterministic
}

// make-scene --unbounded --texture noise: the same geometry (every depth equal), the ground's and pillars' colours from
// non-periodic noise, so that COLMAP can match them: where the checker repeats every 2 units, the noise does not.
TEST_CASE("llff: the unbounded scene's noise texture keeps its geometry and does not repeat") {
  data::UnboundedOptions options;
  options.width_px = 64;
  options.views = 8;
  const auto cameras = data::unbounded_cameras(options);
  size_t differing = 0, rays = 0;
  for (const Camera& camera : cameras) {
    for (int j = 0; j < 12; ++j) {
      for (int i = 0; i < 16; ++i) {
        const Ray ray = camera_ray(camera, 4.0 * i + 2.0, 4.0 * j + 2.0);
        const auto checker = data::trace_unbounded(ray), noise = data::trace_unbounded_noise(ray);
        REQUIRE(checker.t == noise.t);
        differing += checker.rgb != noise.rgb;
        ++rays;
      }
    }
  }
  CHECK(differing > rays / 4);  // the ground and the pillars fill much of every view
  CHECK((data::unbounded_tracer(data::UnboundedTexture::noise) == &data::trace_unbounded_noise));
  CHECK((data::unbounded_tracer(data::UnboundedTexture::checker) == &data::trace_unbounded));
  // Straight down onto the ground at points 2 units apart (well beyond the scene's slab, within the pillars' ring):
  // the checker's colours repeat, the noise's do not, and the noise is not flat either.
  auto ground = [](data::SceneHit (*trace)(const Ray&), double x, double y) {
    Ray down;
    down.origin_world = {x, y, 10.0};
    down.direction_world = {0.0, 0.0, -1.0};
    const auto hit = trace(down);
    REQUIRE(hit.t == doctest::Approx(10.7));
    return hit.rgb;
  };
  size_t noise_repeats = 0;
  double lo = 1, hi = 0;
  for (int k = 0; k < 16; ++k) {
    const double x = 2.3 + 0.37 * k, y = -3.1 + 0.11 * k;
    CHECK(ground(data::trace_unbounded, x, y) == ground(data::trace_unbounded, x + 2, y));
    const auto a = ground(data::trace_unbounded_noise, x, y);
    noise_repeats += a == ground(data::trace_unbounded_noise, x + 2, y);
    lo = std::min(lo, a[0]);
    hi = std::max(hi, a[0]);
  }
  CHECK(noise_repeats == 0);
  CHECK(hi - lo > 0.1);
}

TEST_CASE("llff: malformed captures give one line naming the file") {
  auto expect = [](const fs::path& dir, const std::string& message) {
    data::LoadOptions options;
    options.factor = 4;
    CHECK_THROWS_WITH_AS(data::load_dataset(dir.string(), options), doctest::Contains(message.c_str()), Error);
  };
  const io::NpyArray good = io::read_npy(capture_dir() + "/poses_bounds.npy");
  {
    const auto dir = copy_of_capture("llff-shape");
    io::write_npy((dir / "poses_bounds.npy").string(), std::vector<double>(20 * 16, 1.0), {20, 16});
    expect(dir, "poses_bounds.npy: shape 20x16; expected N x 17");
  }
  {
    const auto dir = copy_of_capture("llff-nan");
    auto values = good.values;
    values[17 * 3 + 5] = std::nan("");
    io::write_npy((dir / "poses_bounds.npy").string(), values, good.shape);
    expect(dir, "poses_bounds.npy: view 3: value 5 is not finite");
  }
  {
    const auto dir = copy_of_capture("llff-bounds");
    auto values = good.values;
    values[17 * 2 + 15] = -1.0;
    io::write_npy((dir / "poses_bounds.npy").string(), values, good.shape);
    expect(dir, "view 2: bounds near -1");
  }
  {
    const auto dir = copy_of_capture("llff-scaled");
    auto values = good.values;
    for (int k : {0, 1, 2}) values[k] *= 2.0;  // a non-rigid rotation
    io::write_npy((dir / "poses_bounds.npy").string(), values, good.shape);
    expect(dir, "view 0");
  }
  {
    const auto dir = copy_of_capture("llff-count");
    fs::remove(dir / "images_4" / "image019.png");
    expect(dir, "19 images, but");
  }
  {
    const auto dir = copy_of_capture("llff-bad-jpeg");
    std::ofstream(dir / "images_4" / "image020.JPG") << "\xff\xd8\xff not really";
    expect(dir, "21 images, but");
    fs::remove(dir / "images_4" / "image000.png");
    expect(dir, "image020.JPG: unreadable JPEG");
  }
  {
    const auto dir = copy_of_capture("llff-noimages");
    fs::remove_all(dir / "images_4");
    fs::remove_all(dir / "images");
    expect(dir, "an LLFF capture without its images");
  }
  {
    // Only another factor's folder (as the downsampled LLFF releases ship): the error names it and the setting.
    const auto dir = copy_of_capture("llff-other-factor");
    fs::remove_all(dir / "images");
    fs::rename(dir / "images_4", dir / "images_8");
    expect(dir, "it holds images_8/: give --set factor=N");
  }
  {
    // Finite but absurd: one camera 1e222 units away (a fuzzed file's; its render path was NaN), or a far bound of
    // 1e230 (both far beyond 1e6 × the nearest bound).
    const auto dir = copy_of_capture("llff-far-away");
    auto values = good.values;
    values[17 * 4 + 3] = 1e222;
    io::write_npy((dir / "poses_bounds.npy").string(), values, good.shape);
    expect(dir, "view 4: position");
    values = good.values;
    values[17 * 6 + 16] = 1e230;
    io::write_npy((dir / "poses_bounds.npy").string(), values, good.shape);
    expect(dir, "view 6: position");
  }
  {
    const auto dir = copy_of_capture("llff-notnpy");
    std::ofstream(dir / "poses_bounds.npy", std::ios::trunc) << "not numpy";
    expect(dir, "poses_bounds.npy: not a .npy file");
  }
}
