// Our lens models (core/lens.hpp) and the rays behind them against COLMAP's own camera models
// (tests/official/fixtures/colmap_lenses.json, written by make_lens_vectors.py through pycolmap, COLMAP's C++ models):
// img_from_cam (the forward model) and cam_from_img (its inverse, the normalised point a pixel's ray goes through)
// for every lens row with coefficients (SIMPLE_RADIAL, RADIAL, OPENCV, OPENCV_FISHEYE, FULL_OPENCV) on a 640×480
// camera.
#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "core/lens.hpp"
#include "core/lens_models.hpp"
#include "official_fixtures.hpp"

using namespace mipnerf;

namespace {

io::Json lens_fixture() {
  const auto path = official::fixture_dir() / "colmap_lenses.json";
  INFO("fixture " << path.string() << " (set MIPNERF_OFFICIAL_FIXTURES if the sources moved)");
  REQUIRE(std::filesystem::is_regular_file(path));
  return io::read_json(path.string());
}

struct FixtureCamera {
  std::string model;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  Lens lens;
  uint32_t width = 0, height = 0;
};

// The fixture's COLMAP parameter list as intrinsics and a lens, read through the model's row (core/lens_models.hpp):
// the row's parameter order is what this pins against COLMAP's.
FixtureCamera camera_of(const io::Json& json) {
  FixtureCamera c;
  c.model = json.at("model").get<std::string>();
  c.width = json.at("width").get<uint32_t>();
  c.height = json.at("height").get<uint32_t>();
  const LensRow* row = find_lens_row(c.model);
  REQUIRE_MESSAGE(row, c.model << " has no lens row");
  const ColmapIntrinsics in = read_colmap_params(*row, json.at("params").get<std::vector<double>>(), c.model);
  c.fx = in.fx;
  c.fy = in.fy;
  c.cx = in.cx;
  c.cy = in.cy;
  c.lens = in.lens;
  REQUIRE(!c.lens.is_pinhole());
  return c;
}

}  // namespace

// COLMAP's forward model and ours are the same polynomials in double precision: agreement to 1e-9 px is roundoff.
TEST_CASE("lens distortion matches COLMAP's img_from_cam for every lens model with coefficients") {
  const io::Json fixture = lens_fixture();
  // Every row that takes coefficients has its camera in the fixture (make_lens_vectors.py's CAMERAS).
  size_t lens_rows_with_coefficients = 0;
  for (const auto& row : lens_rows()) lens_rows_with_coefficients += row.coefficients.empty() ? 0 : 1;
  REQUIRE(fixture.at("cameras").size() == lens_rows_with_coefficients);
  for (const auto& json : fixture.at("cameras")) {
    const FixtureCamera c = camera_of(json);
    const auto points = official::flat(json.at("points"));
    const auto projected = official::flat(json.at("img_from_cam"));
    REQUIRE(points.size() == projected.size());
    double worst_px = 0;
    for (size_t i = 0; i < points.size() / 2; ++i) {
      const Uv distorted = distort(c.lens, {points[2 * i], points[2 * i + 1]});
      worst_px = std::max({worst_px, std::abs(c.fx * distorted[0] + c.cx - projected[2 * i]),
                           std::abs(c.fy * distorted[1] + c.cy - projected[2 * i + 1])});
    }
    INFO(c.model << ": worst difference " << worst_px << " px over " << points.size() / 2 << " points");
    CHECK(worst_px < 1e-9);
  }
}

// COLMAP inverts its models iteratively too (IterativeUndistortion, stopping at a step of 1e-10 relative or after 100
// iterations), so the two inverses agree to the looser of the stopping rules: 1e-8 in normalised units is
// 5·10⁻⁶ px at these focal lengths, far below what a ray can resolve. Where a pixel has no ray (beyond a fisheye's
// field) COLMAP returns a point that does not project back onto it; ours says so (undistort → false) and the tables
// refuse such a camera (data/lens_tables.hpp).
TEST_CASE("lens undistortion matches COLMAP's cam_from_img, also at the corners of the image") {
  const io::Json fixture = lens_fixture();
  for (const auto& json : fixture.at("cameras")) {
    const FixtureCamera c = camera_of(json);
    const auto pixels = official::flat(json.at("pixels"));
    const auto expected = official::flat(json.at("cam_from_img"));
    REQUIRE(pixels.size() == expected.size());
    double worst = 0;
    size_t unreachable = 0;
    for (size_t i = 0; i < pixels.size() / 2; ++i) {
      Uv uv;
      const Uv distorted{(pixels[2 * i] - c.cx) / c.fx, (pixels[2 * i + 1] - c.cy) / c.fy};
      if (!undistort(c.lens, distorted, uv)) {
        // Only where no ray exists: COLMAP then returns a point that its own model does not map onto the pixel.
        const Uv back = distort(c.lens, {expected[2 * i], expected[2 * i + 1]});
        const double miss_px = std::hypot(c.fx * (back[0] - distorted[0]), c.fy * (back[1] - distorted[1]));
        INFO(c.model << " pixel (" << pixels[2 * i] << ", " << pixels[2 * i + 1] << "): COLMAP's inverse misses by "
                     << miss_px << " px");
        CHECK(miss_px > 1.0);
        ++unreachable;
        continue;
      }
      worst = std::max({worst, std::abs(uv[0] - expected[2 * i]), std::abs(uv[1] - expected[2 * i + 1])});
    }
    INFO(c.model << ": worst difference " << worst << " (normalised) over " << pixels.size() / 2 << " pixels");
    // The fisheye's corners lie beyond its field (θ_d(θ) < 1.74 for every θ < 90°): 5 of the fixture's pixels.
    CHECK(unreachable == (c.lens.model == LensModel::opencv_fisheye ? 5u : 0u));
    CHECK(worst < 1e-8);
  }
}

// camera_ray (the CPU reference of the ray kernel) goes through COLMAP's undistorted point: the camera-frame direction
// is (u, −v, −1) in OpenGL axes, so a pixel's ray re-projected through COLMAP's forward model lands on the pixel.
TEST_CASE("camera_ray behind a lens re-projects through COLMAP's model onto its pixel") {
  const io::Json fixture = lens_fixture();
  for (const auto& json : fixture.at("cameras")) {
    const FixtureCamera c = camera_of(json);
    Camera camera;
    camera.focal_x_px = c.fx;
    camera.focal_y_px = c.fy;
    camera.center_x_px = c.cx;
    camera.center_y_px = c.cy;
    camera.width_px = c.width;
    camera.height_px = c.height;
    camera.lens = c.lens;
    const auto pixels = official::flat(json.at("pixels"));
    const auto expected = official::flat(json.at("cam_from_img"));
    double worst = 0;
    for (size_t i = 0; i < pixels.size() / 2; ++i) {
      const Ray ray = camera_ray(camera, pixels[2 * i], pixels[2 * i + 1]);  // identity pose: world = camera frame
      if (std::isnan(ray.direction_world[0])) continue;  // beyond the fisheye's field (previous test)
      REQUIRE(ray.direction_world[2] == -1.0);
      worst = std::max({worst, std::abs(ray.direction_world[0] - expected[2 * i]),
                        std::abs(-ray.direction_world[1] - expected[2 * i + 1])});
    }
    INFO(c.model << ": worst difference " << worst);
    CHECK(worst < 1e-8);
  }
}
