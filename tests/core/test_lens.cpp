// core/lens.hpp beyond what COLMAP's fixture covers (tests/official/test_lenses.cpp): the inverse where the lens
// folds or ends, and the inverse in place.
#include <doctest/doctest.h>

#include <cmath>

#include "core/lens.hpp"

using namespace mipnerf;

TEST_CASE("lens: undistort refuses points beyond a fold, and points no ray reaches") {
  // u_d = u·(1 − 3u²) rises to its largest value 2/9 = 0.222 at u = 1/3, then falls: the lens folds at u = 1/3.
  const Lens folding{LensModel::simple_radial, -3.0};
  Uv uv;
  REQUIRE(undistort(folding, {0.2, 0.0}, uv));
  CHECK(uv[0] == doctest::Approx(0.2 * 1.32).epsilon(0.2));  // the root before the fold, u < 1/3
  CHECK(uv[0] < 1.0 / 3.0);
  CHECK_FALSE(undistort(folding, {0.23, 0.0}, uv));  // beyond the largest u_d: no root at all
  // A fisheye maps θ < 90° to θ_d below θ_d(90°); a larger θ_d has no ray in front of the camera.
  const Lens fisheye{LensModel::opencv_fisheye};
  REQUIRE(undistort(fisheye, {1.5, 0.0}, uv));
  CHECK(uv[0] == doctest::Approx(std::tan(1.5)).epsilon(1e-9));
  CHECK_FALSE(undistort(fisheye, {1.6, 0.0}, uv));
}

TEST_CASE("lens: undistort in place (the output array is the input) gives the same answer") {
  const Lens lens{LensModel::opencv, -0.15, 0.04, 0, 0, 0.0012, -0.0008};
  const Uv distorted{0.41, -0.27};
  Uv separate;
  REQUIRE(undistort(lens, distorted, separate));
  Uv in_place = distorted;
  REQUIRE(undistort(lens, in_place, in_place));
  CHECK(in_place[0] == separate[0]);
  CHECK(in_place[1] == separate[1]);
  const Uv back = distort(lens, separate);
  CHECK(std::abs(back[0] - distorted[0]) < 1e-12);
  CHECK(std::abs(back[1] - distorted[1]) < 1e-12);
}
