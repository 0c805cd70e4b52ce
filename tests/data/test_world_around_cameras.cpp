// A transforms.json of photos taken all around (what `dataset from-photos` writes for a capture that is not
// forward-facing): detected as 360°, an unbounded scene for Zip-NeRF, and loaded for an unbounded run in the world its
// contraction expects (centred where the cameras look, RMS camera distance 1), the same world an LLFF capture of the
// same cameras gets from spherify, whatever split is loaded.
#include <doctest/doctest.h>

#include <cmath>

#include "data/dataset.hpp"
#include "data/formats/formats.hpp"
#include "data/formats/llff_capture.hpp"
#include "data/synthetic/unbounded.hpp"
#include "support/data_fixtures.hpp"
#include "support/temp_scene.hpp"
#include "train/model.hpp"
#include "train/scene_effects.hpp"

using namespace mipnerf;

namespace {

double distance(const Camera& a, const Camera& b) {
  return std::hypot(a.camera_to_world[3] - b.camera_to_world[3], a.camera_to_world[7] - b.camera_to_world[7],
                    a.camera_to_world[11] - b.camera_to_world[11]);
}

double norm_of_position(const Camera& camera) {
  return std::hypot(camera.camera_to_world[3], camera.camera_to_world[7], camera.camera_to_world[11]);
}

// The opaque photos of `dir` (an LLFF capture, images/) as a transforms.json beside them, in a world moved by
// `offset` and scaled by `scale` (as a COLMAP import leaves it: another origin, another unit), near/far as given.
void write_as_transforms_json(const std::string& dir, const Vec3& offset, double scale) {
  data::LoadOptions as_taken;
  as_taken.llff.ndc = false;  // world cameras, as taken
  as_taken.holdout_every = 0;
  const data::Dataset llff = data::load_dataset(dir, as_taken);
  const data::Split& split = llff.split("train");
  io::Json frames = io::Json::array();
  for (size_t i = 0; i < split.num_images(); ++i) {
    data::Matrix34 pose = split.cameras[i].camera_to_world;
    for (int r = 0; r < 3; ++r) pose[4 * r + 3] = scale * pose[4 * r + 3] + offset[r];
    const Camera& c = split.cameras[i];
    frames.push_back({{"file_path", std::filesystem::relative(split.files[i], dir).string()},
                      {"transform_matrix", data::pose_to_json(pose)},
                      {"fl_x", c.focal_x_px},
                      {"fl_y", c.focal_y_px},
                      {"cx", c.center_x_px},
                      {"cy", c.center_y_px},
                      {"w", c.width_px},
                      {"h", c.height_px}});
  }
  io::write_json(dir + "/transforms.json", {{"near", 2.0}, {"far", 60.0}, {"frames", frames}});
}

}  // namespace

TEST_CASE("transforms.json: photos taken all around are an unbounded scene, loaded in the world spherify gives") {
  const auto dir = test::fresh_temp_dir("transforms-360");
  data::UnboundedOptions scene;
  scene.width_px = 32;
  scene.views = 17;  // 3 held out, 14 trained
  scene.samples_per_axis = 1;
  scene.threads = 2;
  data::write_unbounded_scene(dir.string(), scene);
  // The LLFF capture spherified, read before the transforms.json beside it (which a folder's detection prefers).
  data::LoadOptions spherified;
  spherified.llff.spherify = true;
  spherified.llff.ndc = false;
  const std::vector<Camera> llff = test::every_camera_in_file_order(data::load_dataset(dir.string(), spherified));
  write_as_transforms_json(dir.string(), {30.0, -12.0, 5.0}, 4.0);
  const std::string file = (dir / "transforms.json").string();

  // The traits come from the poses: all around, no alpha (photos).
  const auto traits = data::scene_traits(file, data::LoadOptions{});
  CHECK(traits.format == data::DatasetFormat::transforms_json);
  CHECK(traits.all_around);
  CHECK(!traits.has_alpha);
  // mip-NeRF: the photos' effects (cones, black background) and mip-NeRF 360's group; Zip-NeRF: its own.
  const train::SceneEffects mip = train::scene_effects(file, 1);
  CHECK(mip.settings == std::map<std::string, std::string>{{"ray_shape", "cone"}, {"background", "black"}});
  CHECK(mip.zipnerf_settings.empty());
  CHECK(mip.mipnerf_settings.at("unbounded") == "true");
  CHECK(mip.summary == "transforms.json of photos taken all around (360°) → cones, black background");
  const train::SceneEffects zip = train::scene_effects(file, 1, train::ModelFamily::zipnerf);
  CHECK(zip.zipnerf_settings.at("unbounded") == "true");
  CHECK(zip.zipnerf_settings.at("sampler") == "proposal");
  std::string line;
  const auto settings = train::with_scene_effects(zip, {}, line);
  const train::TrainConfig config = train::resolve_config("fast", "zipnerf", settings);
  REQUIRE(config.unbounded);

  // What an unbounded run loads: centred where the cameras look, at RMS distance 1; near/far as the run sets them.
  const data::LoadOptions options = train::load_options(config, file, {}, 1);
  CHECK(options.world_around_cameras);
  const data::Dataset unbounded = data::load_dataset(file, options);
  const std::vector<Camera> cameras = test::every_camera_in_file_order(unbounded);
  REQUIRE(cameras.size() == 17);
  double mean_square = 0.0;
  for (const Camera& c : cameras) mean_square += norm_of_position(c) * norm_of_position(c) / 17.0;
  CHECK(mean_square == doctest::Approx(1.0).epsilon(1e-12));
  CHECK(cameras[0].near == train::kUnboundedNear);
  CHECK(cameras[0].far == train::kUnboundedFar);
  // The look-at point is the origin: the cameras' optical axes pass it as closely as least squares allows.
  const auto look_at = data::closest_point_to_axes(cameras);
  REQUIRE(look_at.has_value());
  CHECK(std::hypot((*look_at)[0], (*look_at)[1], (*look_at)[2]) < 1e-9);

  // The same cameras read as the LLFF capture and spherified (the measured path, bench/results/unbounded): the same
  // distances between every pair of cameras and from the centre (spherify also turns the world; the contraction does
  // not care).
  REQUIRE(llff.size() == cameras.size());
  for (size_t i = 0; i < cameras.size(); ++i) {
    CAPTURE(i);
    CHECK(norm_of_position(cameras[i]) == doctest::Approx(norm_of_position(llff[i])).epsilon(1e-9));
    for (size_t j = 0; j < i; ++j) {
      CHECK(distance(cameras[i], cameras[j]) == doctest::Approx(distance(llff[i], llff[j])).epsilon(1e-9));
    }
  }

  // One world whatever is loaded: the held-out split alone has the cameras it has in the whole load.
  data::LoadOptions test_only = options;
  test_only.splits = {"test"};
  const data::Dataset held_out = data::load_dataset(file, test_only);
  const data::Split& test = held_out.split("test");
  REQUIRE(test.num_images() == 3);
  for (size_t i = 0; i < 3; ++i) CHECK(test.cameras[i].camera_to_world == cameras[8 * i].camera_to_world);

  // Near/far from the file move with the world (x its scale); given ones are in the new units already. The stored
  // world's own look-at point and RMS distance give the expected move.
  data::LoadOptions as_stored;
  as_stored.holdout_every = 0;
  const std::vector<Camera> stored = data::load_dataset(file, as_stored).split("train").cameras;
  CHECK(stored[0].near == 2.0);
  const auto stored_centre = data::closest_point_to_axes(stored);
  REQUIRE(stored_centre.has_value());
  double stored_square = 0.0;
  for (const Camera& c : stored) {
    const Vec3 offset = sub(data::camera_center(c), *stored_centre);
    stored_square += dot(offset, offset) / static_cast<double>(stored.size());
  }
  const double scale = 1.0 / std::sqrt(stored_square);
  data::LoadOptions file_bounds = as_stored;
  file_bounds.world_around_cameras = true;
  const Camera first = data::load_dataset(file, file_bounds).split("train").cameras[0];
  CHECK(first.near == doctest::Approx(2.0 * scale).epsilon(1e-12));
  CHECK(first.far == doctest::Approx(60.0 * scale).epsilon(1e-12));
  for (int r = 0; r < 3; ++r) {
    CHECK(first.camera_to_world[4 * r + 3] ==
          doctest::Approx(scale * (stored[0].camera_to_world[4 * r + 3] - (*stored_centre)[r])).epsilon(1e-12));
  }
  file_bounds.near = 0.5;
  CHECK(data::load_dataset(file, file_bounds).split("train").cameras[0].near == 0.5);
}

TEST_CASE("transforms.json: a rendered object seen from all around stays bounded, and forward photos are not 360") {
  test::TempDir dir;
  test::write_blender_split(dir.path(), "train", 9, 8, 6);  // cameras around the origin, RGBA with alpha
  io::Json blender = io::read_json(dir / "transforms_train.json");
  const double focal = 0.5 * 8 / std::tan(0.35);
  io::Json single = {{"fl_x", focal}, {"fl_y", focal}, {"cx", 4.0}, {"cy", 3.0}, {"w", 8}, {"h", 6},
                     {"frames", blender["frames"]}};
  io::write_json(dir / "transforms.json", single);
  const auto traits = data::scene_traits(dir / "transforms.json", data::LoadOptions{});
  CHECK(traits.all_around);
  CHECK(traits.has_alpha);
  CHECK(train::scene_effects(dir / "transforms.json", 1, train::ModelFamily::zipnerf).zipnerf_settings.empty());
  CHECK(train::scene_effects(dir / "transforms.json", 1).mipnerf_settings.empty());

  // Forward-facing: every camera looks along −y from a small patch.
  for (size_t k = 0; k < single["frames"].size(); ++k) {
    const double x = 0.1 * static_cast<double>(k);
    single["frames"][k]["transform_matrix"] =
        data::pose_to_json(data::look_at_pose({x, 4.0, 0.0}, {x, 0.0, 0.0}, {0, 0, 1}));
  }
  io::write_json(dir / "transforms.json", single);
  CHECK(!data::scene_traits(dir / "transforms.json", data::LoadOptions{}).all_around);

  // Parallel axes meet nowhere: the world is centred on the mean camera (x 0.4, y 4), still at RMS distance 1.
  std::vector<data::Matrix34> poses;
  for (size_t k = 0; k < single["frames"].size(); ++k) {
    poses.push_back(data::pose_from_json(single["frames"][k]["transform_matrix"], "frame"));
  }
  const data::WorldAroundCameras world = data::world_around_cameras(poses, "transforms.json");
  CHECK(!world.centre_is_look_at);
  CHECK(world.centre[0] == doctest::Approx(0.4));
  CHECK(world.centre[1] == doctest::Approx(4.0));
  // Nine cameras 0.1 apart along x around their mean: RMS distance sqrt(mean of (0.1 (k - 4))^2) = sqrt(0.0666...).
  CHECK(world.scale == doctest::Approx(1.0 / std::sqrt(0.06666666666666667)));
  // Cameras all in one place give no unit: refused, naming the file.
  const std::vector<data::Matrix34> same(3, poses[0]);
  CHECK(test::contains(test::error_of([&] { data::world_around_cameras(same, "x/transforms.json"); }),
                       "x/transforms.json: every camera sits at the scene's centre"));
}
