// Split summaries (data/inspect): where the cameras look. An inward-looking capture has a look-at centre in front of
// every camera; a forward-facing capture's nearly parallel axes meet behind its cameras, so its viewing direction and
// the spread of its axes are what describe it.
#include <doctest/doctest.h>

#include <cmath>

#include "data/inspect.hpp"
#include "support/data_fixtures.hpp"

using namespace mipnerf;

namespace {

// One-pixel images of the given poses.
data::Split split_of(const std::vector<data::Matrix34>& poses) {
  data::Split split;
  split.name = "train";
  for (const auto& pose : poses) {
    Camera camera;
    camera.camera_to_world = pose;
    split.cameras.push_back(camera);
    split.scale_levels.push_back(0);
    split.pixel_offsets.push_back(split.pixel_offsets.back() + 1);
    split.rgb.insert(split.rgb.end(), {0.5f, 0.5f, 0.5f});
  }
  return split;
}

}  // namespace

TEST_CASE("inspect: a forward-facing capture has a viewing direction and a spread, its axes meeting behind it") {
  // A 3x3 grid in the plane z = 0, each camera turned outward a little: its target is (1.1 x, 1.1 y, -10).
  std::vector<data::Matrix34> poses;
  for (int i = -1; i <= 1; ++i) {
    for (int j = -1; j <= 1; ++j) {
      const Vec3 eye{0.5 * i, 0.4 * j, 0.0};
      poses.push_back(data::look_at_pose(eye, {1.1 * eye[0], 1.1 * eye[1], -10.0}, {0, 1, 0}));
    }
  }
  const data::SplitSummary s = data::summarize(split_of(poses));
  CHECK(s.forward_facing);
  CHECK(s.view_direction[0] == doctest::Approx(0.0).epsilon(1e-12));
  CHECK(s.view_direction[1] == doctest::Approx(0.0).epsilon(1e-12));
  CHECK(s.view_direction[2] == doctest::Approx(-1.0).epsilon(1e-12));
  // The corner cameras are the farthest off: atan(0.1 · |(0.5, 0.4)| / 10).
  const double corner_deg = std::atan(0.1 * std::hypot(0.5, 0.4) / 10.0) * 180.0 / M_PI;
  CHECK(s.axis_spread_deg == doctest::Approx(corner_deg).epsilon(1e-9));
  // Diverging axes meet behind the cameras: the look-at centre is in front of none (what inspect no longer shows).
  REQUIRE(s.look_at.has_value());
  CHECK(s.cameras_facing == 0);
}

TEST_CASE("inspect: an inward-looking capture has its look-at centre in front of every camera") {
  std::vector<data::Matrix34> poses;
  for (int k = 0; k < 6; ++k) poses.push_back(test::test_pose(k));
  const data::SplitSummary s = data::summarize(split_of(poses));
  CHECK_FALSE(s.forward_facing);
  REQUIRE(s.look_at.has_value());
  for (int k = 0; k < 3; ++k) CHECK((*s.look_at)[k] == doctest::Approx(0.0).scale(1.0).epsilon(1e-9));
  CHECK(s.cameras_facing == 6);
  CHECK(s.axis_spread_deg > 45.0);
}
