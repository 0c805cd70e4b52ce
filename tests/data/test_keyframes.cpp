// Keyframe interpolation (data/keyframes): the path passes through its keyframes, every frame's rotation stays a
// rotation, two keyframes give the straight line at constant speed and the half-way turn, and bad input is refused.
#include <doctest/doctest.h>

#include <cmath>

#include "core/error.hpp"
#include "core/vec3.hpp"
#include "data/paths/keyframes.hpp"
#include "data/pose.hpp"

using namespace mipnerf;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A camera at `eye` looking at the origin, 16×12 pixels.
Camera looking_at_origin(const Vec3& eye) {
  Camera c;
  c.camera_to_world = data::look_at_pose(eye, {0, 0, 0}, {0, 0, 1});
  c.width_px = 16;
  c.height_px = 12;
  c.focal_x_px = c.focal_y_px = 20.0;
  c.center_x_px = 8.0;
  c.center_y_px = 6.0;
  return c;
}

// Largest |RᵀR − I| entry, and det R, of a pose's rotation.
double orthonormality_error(const std::array<double, 12>& m) {
  double worst = 0.0;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      double d = 0.0;
      for (int r = 0; r < 3; ++r) d += m[4 * r + a] * m[4 * r + b];
      worst = std::max(worst, std::abs(d - (a == b ? 1.0 : 0.0)));
    }
  }
  return worst;
}

double determinant(const std::array<double, 12>& m) {
  return m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
         m[2] * (m[4] * m[9] - m[5] * m[8]);
}

// Rotation about the axis (unit) by `angle` radians, as a 3×4 pose at the origin (Rodrigues).
std::array<double, 12> rotation_about(const Vec3& axis, double angle) {
  const double c = std::cos(angle), s = std::sin(angle), t = 1 - c;
  const double x = axis[0], y = axis[1], z = axis[2];
  return {t * x * x + c,     t * x * y - s * z, t * x * z + s * y, 0, t * x * y + s * z, t * y * y + c,
          t * y * z - s * x, 0,                 t * x * z - s * y, t * y * z + s * x, t * z * z + c, 0};
}

}  // namespace

TEST_CASE("keyframes: a rotation survives the trip through its quaternion, half turns included") {
  const Vec3 axes[] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, normalize(Vec3{1, 2, 3}), normalize(Vec3{-3, 1, 0.5})};
  for (const Vec3& axis : axes) {
    for (double angle : {0.0, 0.3, 1.7, kPi - 1e-9, kPi, -2.5}) {
      CAPTURE(angle);
      const auto pose = rotation_about(axis, angle);
      const auto back = data::quaternion_to_rotation(data::rotation_to_quaternion(pose));
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) CHECK(back[3 * r + c] == doctest::Approx(pose[4 * r + c]).epsilon(1e-12));
      }
    }
  }
}

TEST_CASE("keyframes: the path passes through every keyframe and every frame is a rotation") {
  const std::vector<Camera> keys = {looking_at_origin({4, 0, 1}), looking_at_origin({0, 4, 2}),
                                    looking_at_origin({-4, 0, 1}), looking_at_origin({0, -3, 0.5})};
  const uint32_t per_segment = 5;
  const auto frames = data::interpolate_keyframes(keys, 1 + per_segment * 3);
  REQUIRE(frames.size() == 16);
  for (size_t k = 0; k < keys.size(); ++k) {
    CAPTURE(k);
    CHECK(frames[k * per_segment].camera_to_world == keys[k].camera_to_world);  // bit for bit
  }
  for (const Camera& c : frames) {
    CHECK(orthonormality_error(c.camera_to_world) < 1e-12);
    CHECK(determinant(c.camera_to_world) == doctest::Approx(1.0).epsilon(1e-12));
    CHECK(c.width_px == 16);
    CHECK(c.height_px == 12);
  }
  // A smooth path: no step between consecutive frames more than twice the mean step.
  double total = 0.0, largest = 0.0;
  for (size_t i = 1; i < frames.size(); ++i) {
    const double step = length(sub(data::camera_center(frames[i]), data::camera_center(frames[i - 1])));
    total += step;
    largest = std::max(largest, step);
  }
  CHECK(largest < 2.0 * total / static_cast<double>(frames.size() - 1));
}

TEST_CASE("keyframes: two keyframes give the straight line at constant speed and the half-way rotation") {
  Camera a = looking_at_origin({4, 0, 0});
  Camera b = a;
  b.camera_to_world = rotation_about({0, 0, 1}, kPi / 2);
  b.camera_to_world[3] = 0.0;  // b's centre: (0, 2, 1)
  b.camera_to_world[7] = 2.0;
  b.camera_to_world[11] = 1.0;
  a.camera_to_world = rotation_about({0, 0, 1}, 0.0);
  a.camera_to_world[3] = 4.0;
  b.focal_x_px = 40.0;
  const auto frames = data::interpolate_keyframes({a, b}, 5);
  for (int i = 0; i < 5; ++i) {
    CAPTURE(i);
    const double t = i / 4.0;
    const Vec3 centre = data::camera_center(frames[i]);
    CHECK(centre[0] == doctest::Approx(4.0 - 4.0 * t).epsilon(1e-12));
    CHECK(centre[1] == doctest::Approx(2.0 * t).epsilon(1e-12));
    CHECK(centre[2] == doctest::Approx(t).epsilon(1e-12));
    CHECK(frames[i].focal_x_px == doctest::Approx(20.0 + 20.0 * t));
    // The rotation about z by 90°·t: its first column is (cos, sin, 0).
    CHECK(frames[i].camera_to_world[0] == doctest::Approx(std::cos(kPi / 2 * t)).epsilon(1e-12));
    CHECK(frames[i].camera_to_world[4] == doctest::Approx(std::sin(kPi / 2 * t)).epsilon(1e-12));
  }
}

TEST_CASE("keyframes: one keyframe repeats, and bad input is refused with what to change") {
  const Camera a = looking_at_origin({4, 0, 1});
  const auto copies = data::interpolate_keyframes({a}, 3);
  REQUIRE(copies.size() == 3);
  CHECK(copies[2].camera_to_world == a.camera_to_world);
  CHECK_THROWS_AS(data::interpolate_keyframes({}, 10), Error);
  CHECK_THROWS_AS(data::interpolate_keyframes({a}, 0), Error);
  CHECK_THROWS_WITH_AS(data::interpolate_keyframes({a, a, a}, 2), doctest::Contains("would skip keyframes"), Error);
  Camera wide = a;
  wide.width_px = 32;
  CHECK_THROWS_WITH_AS(data::interpolate_keyframes({a, wide}, 10), doctest::Contains("share one image size"), Error);
}
