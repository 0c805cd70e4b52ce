// Camera rays behind a lens (kernels/rays.cl, LENS_TABLES): the kernel reads each pixel's undistorted point and
// footprint radius from the lens tables (data/lens_tables.hpp). Checked three ways: against the reference mirror
// (ref::rays_fwd with the same tables, double precision), by projecting each float32 ray back through COLMAP's
// forward model to its pixel centre (< 1e-4 px), and each radius against the footprint measured independently from
// camera_ray of the pixel's neighbours. Pinhole cameras in the same batch keep the pinhole formula.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "core/camera.hpp"
#include "core/lens.hpp"
#include "data/lens_tables.hpp"
#include "kernel_checks.hpp"
#include "ops/rays.hpp"
#include "ref/rays.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;

namespace {

constexpr double kRadiusPerPixelWidth = 0.57735026918962576451;  // 2/√12

// A rotation about the axis (1, 2, 3)/√14 by `angle`, so no camera looks along an axis.
void rotate(Camera& cam, double angle) {
  const double n = std::sqrt(14.0), x = 1 / n, y = 2 / n, z = 3 / n, c = std::cos(angle), s = std::sin(angle);
  const double r[9] = {c + x * x * (1 - c),     x * y * (1 - c) - z * s, x * z * (1 - c) + y * s,
                       y * x * (1 - c) + z * s, c + y * y * (1 - c),     y * z * (1 - c) - x * s,
                       z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)};
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) cam.camera_to_world[4 * row + col] = r[3 * row + col];
  }
}

// An OPENCV camera (barrel, with tangential terms), an OPENCV_FISHEYE camera seeing ≈ 166° across its diagonal, and a
// pinhole, all 64×48 with the principal point off the centre.
std::vector<Camera> lens_cameras() {
  std::vector<Camera> cams(3);
  for (size_t c = 0; c < cams.size(); ++c) {
    Camera& cam = cams[c];
    cam.width_px = 64;
    cam.height_px = 48;
    cam.center_x_px = 31.25;
    cam.center_y_px = 24.5;
    cam.focal_x_px = 52;
    cam.focal_y_px = 50;
    rotate(cam, 0.7 + c);
    cam.camera_to_world[3] = 0.3 * c;
    cam.camera_to_world[7] = -1.5;
    cam.camera_to_world[11] = 2.0;
  }
  cams[0].lens = {LensModel::opencv, -0.12, 0.03, 0, 0, 0.0015, -0.0008};
  cams[1].lens = {LensModel::opencv_fisheye, 0.02, -0.01, 0.002, -0.0005};
  cams[1].focal_x_px = cams[1].focal_y_px = 26;  // the corner pixel ≈ 83° from the axis
  return cams;
}

struct LensBatch {
  std::vector<Camera> cameras;
  data::LensTables tables;
  std::vector<float> packed;
  std::vector<uint32_t> camera_ids, pixel_ids;
};

LensBatch lens_batch(size_t n_rays) {
  LensBatch b;
  b.cameras = lens_cameras();
  b.tables = data::build_lens_tables(b.cameras);
  b.packed = pack_cameras(b.cameras);
  data::set_lens_table_slots(b.packed, b.tables);
  std::mt19937 rng(27);
  for (size_t i = 0; i < n_rays; ++i) {
    const uint32_t c = static_cast<uint32_t>(i % b.cameras.size());
    b.camera_ids.push_back(c);
    b.pixel_ids.push_back(static_cast<uint32_t>(rng() % (b.cameras[c].width_px * b.cameras[c].height_px)));
  }
  // Every corner of each camera, where the lenses bend the most.
  for (uint32_t c = 0; c < b.cameras.size(); ++c) {
    const uint32_t w = b.cameras[c].width_px, h = b.cameras[c].height_px;
    for (uint32_t p : {0u, w - 1, (h - 1) * w, h * w - 1}) {
      b.camera_ids.push_back(c);
      b.pixel_ids.push_back(p);
    }
  }
  return b;
}

struct DeviceRays {
  std::vector<float> origins, directions, viewdirs, radii;
};

DeviceRays run_device(const RaysOptions& options, const LensBatch& b, const RngKey& key) {
  auto& ctx = test::test_context();
  const size_t n = b.camera_ids.size();
  auto cameras = test::upload(ctx, b.packed, "cameras");
  auto ids = test::upload(ctx, b.camera_ids, "camera_ids"), pixels = test::upload(ctx, b.pixel_ids, "pixel_ids");
  auto tables = test::upload(ctx, b.tables.values, "lens tables");
  auto rays = test::filled_rays(ctx, n, 7.0f);
  ops::Rays(ctx, options).fwd({cameras, ids, pixels, n, &tables}, rays, key);
  return {rays.origins.download(ctx), rays.directions.download(ctx), rays.viewdirs.download(ctx),
          rays.radii.download(ctx)};
}

// The pixel position a world direction of camera `cam` projects to through its lens (COLMAP's forward model).
std::array<double, 2> project(const Camera& cam, const double dir_world[3]) {
  const auto& m = cam.camera_to_world;
  double d[3];  // camera frame: the rotation's transpose
  for (int a = 0; a < 3; ++a) d[a] = m[a] * dir_world[0] + m[4 + a] * dir_world[1] + m[8 + a] * dir_world[2];
  const Uv undistorted = {d[0] / -d[2], -d[1] / -d[2]};  // OpenGL (x right, y up, −z ahead) to OpenCV (u, v)
  const Uv distorted = distort(cam.lens, undistorted);
  return {cam.focal_x_px * distorted[0] + cam.center_x_px, cam.focal_y_px * distorted[1] + cam.center_y_px};
}

double distance(const Ray& a, const Ray& b) {
  return std::hypot(a.direction_world[0] - b.direction_world[0], a.direction_world[1] - b.direction_world[1],
                    a.direction_world[2] - b.direction_world[2]);
}

}  // namespace

TEST_CASE("rays: behind a lens, each float32 ray projects back through COLMAP's model to its pixel centre") {
  RaysOptions options;
  options.lens_tables = true;
  const LensBatch b = lens_batch(300);
  const DeviceRays rays = run_device(options, b, {});
  double worst_px = 0.0, worst_radius = 0.0;
  for (size_t i = 0; i < b.camera_ids.size(); ++i) {
    const Camera& cam = b.cameras[b.camera_ids[i]];
    const uint32_t px = b.pixel_ids[i] % cam.width_px, py = b.pixel_ids[i] / cam.width_px;
    const double dir[3] = {rays.directions[3 * i], rays.directions[3 * i + 1], rays.directions[3 * i + 2]};
    const auto pixel = project(cam, dir);
    worst_px = std::max({worst_px, std::abs(pixel[0] - (px + 0.5)), std::abs(pixel[1] - (py + 0.5))});
    // The footprint measured here, from camera_ray (which undistorts through core/lens): the mean distance to the
    // next pixel's direction across and down (the previous one in the last column / row), × 2/√12.
    const Ray here = camera_ray(cam, px + 0.5, py + 0.5);
    const double across = distance(here, camera_ray(cam, px + (px + 1 < cam.width_px ? 1.5 : -0.5), py + 0.5));
    const double down = distance(here, camera_ray(cam, px + 0.5, py + (py + 1 < cam.height_px ? 1.5 : -0.5)));
    const double footprint = cam.lens.is_pinhole() ? kRadiusPerPixelWidth / cam.focal_x_px
                                                   : 0.5 * (across + down) * kRadiusPerPixelWidth;
    worst_radius = std::max(worst_radius, std::abs(rays.radii[i] - footprint) / footprint);
  }
  MESSAGE("worst reprojection " << worst_px << " px, worst radius " << worst_radius << " relative");
  CHECK(worst_px < 1e-4);
  CHECK(worst_radius < 1e-5);
  // The fisheye's rim pixels cover far more of the sphere of directions per pixel than its centre: their cones are
  // wider (in angle) as the lens says, not the pinhole's 1/f everywhere.
  const Camera& fisheye = b.cameras[1];
  const Ray centre = camera_ray(fisheye, 32.5, 24.5), right = camera_ray(fisheye, 33.5, 24.5);
  const Ray rim = camera_ray(fisheye, 0.5, 0.5), rim_next = camera_ray(fisheye, 1.5, 0.5);
  auto angle = [](const Ray& a, const Ray& c) {
    const auto& p = a.direction_world;
    const auto& q = c.direction_world;
    const double dot = p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
    return std::acos(dot / std::sqrt((p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) * (q[0] * q[0] + q[1] * q[1] + q[2] * q[2])));
  };
  CHECK(angle(rim, rim_next) < angle(centre, right));  // an equidistant-like fisheye: per-pixel angle shrinks slowly
  CHECK(distance(rim, rim_next) > 3 * distance(centre, right));  // at unit depth the rim's footprint is far wider
}

TEST_CASE("rays: behind a lens, the kernel is the reference mirror, at the centre, offset and jittered") {
  const LensBatch b = lens_batch(200);
  std::vector<double> tables(b.tables.values.begin(), b.tables.values.end());
  for (bool jitter : {false, true}) {
    for (float offset : {0.5f, 0.0f}) {
      if (jitter && offset == 0.0f) continue;
      for (bool unit_viewdirs : {true, false}) {
        RaysOptions options;
        options.lens_tables = true;
        options.jitter_subpixel = jitter;
        options.pixel_center_offset = offset;
        options.unit_viewdirs = unit_viewdirs;
        INFO("jitter " << jitter << ", offset " << offset << ", unit viewdirs " << unit_viewdirs);
        const RngKey key{11, 3, 100};
        const DeviceRays rays = run_device(options, b, key);
        std::vector<double> ro, rd, rv, rr, rn, rf, rl;
        ref::rays_fwd(options, test::to_double(b.packed), b.camera_ids, b.pixel_ids, ro, rd, rv, rr, rn, rf, rl,
                      b.camera_ids.size(), b.cameras.size(), key, tables);
        // Each output is a few float32 operations on float32 table entries of size ≤ 4: within 1e-6 absolute.
        for (size_t k = 0; k < rd.size(); ++k) {
          REQUIRE(std::abs(rays.directions[k] - rd[k]) < 1e-6 * (1 + std::abs(rd[k])));
          REQUIRE(std::abs(rays.viewdirs[k] - rv[k]) < 1e-6 * (1 + std::abs(rv[k])));
          REQUIRE(rays.origins[k] == doctest::Approx(ro[k]).epsilon(1e-6));
        }
        for (size_t k = 0; k < rr.size(); ++k) REQUIRE(rays.radii[k] == doctest::Approx(rr[k]).epsilon(1e-6));
      }
    }
  }
}

TEST_CASE("rays: behind a lens, off the pixel centre, first order in the offset, near the exact point") {
  // A jittered ray's point is the table's centre moved along the differences to its neighbours: the exact
  // undistortion of (x + ξ, y + ξ) differs by the lens's curvature over half a pixel.
  const LensBatch b = lens_batch(0);
  std::vector<double> tables(b.tables.values.begin(), b.tables.values.end());
  RaysOptions options;
  options.lens_tables = true;
  options.pixel_center_offset = 0.1f;
  std::vector<uint32_t> ids, pixels;
  for (uint32_t c = 0; c < 2; ++c) {
    for (uint32_t p = 0; p < 64 * 48; p += 37) {
      ids.push_back(c);
      pixels.push_back(p);
    }
  }
  std::vector<double> ro, rd, rv, rr, rn, rf, rl;
  ref::rays_fwd(options, test::to_double(b.packed), ids, pixels, ro, rd, rv, rr, rn, rf, rl, ids.size(),
                b.cameras.size(), {}, tables);
  double worst_px[2] = {0.0, 0.0};
  for (size_t i = 0; i < ids.size(); ++i) {
    const Camera& cam = b.cameras[ids[i]];
    const auto pixel = project(cam, &rd[3 * i]);
    const uint32_t px = pixels[i] % cam.width_px, py = pixels[i] / cam.width_px;
    worst_px[ids[i]] = std::max({worst_px[ids[i]], std::abs(pixel[0] - (px + 0.1)), std::abs(pixel[1] - (py + 0.1))});
  }
  MESSAGE("first-order offset 0.4 px from the centre: OPENCV worst " << worst_px[0] << " px, fisheye (rim at 83°) "
                                                                      << worst_px[1] << " px from the exact point");
  CHECK(worst_px[0] < 0.01);
  // At the fisheye's rim u = tan θ bends sharply across one pixel: the point lands within a fifth of a pixel of the
  // exact one, inside the pixel it samples.
  CHECK(worst_px[1] < 0.2);
}

TEST_CASE("rays: behind a lens, a stage without LENS_TABLES refuses tables, one with it needs them") {
  auto& ctx = test::test_context();
  const LensBatch b = lens_batch(4);
  auto cameras = test::upload(ctx, b.packed, "cameras");
  auto ids = test::upload(ctx, b.camera_ids, "camera_ids"), pixels = test::upload(ctx, b.pixel_ids, "pixel_ids");
  auto tables = test::upload(ctx, b.tables.values, "lens tables");
  auto rays = test::filled_rays(ctx, b.camera_ids.size(), 0.0f);
  const size_t n = b.camera_ids.size();
  CHECK_THROWS_WITH(ops::Rays(ctx, {}).fwd({cameras, ids, pixels, n, &tables}, rays),
                    doctest::Contains("built without LENS_TABLES"));
  RaysOptions lens;
  lens.lens_tables = true;
  CHECK_THROWS_WITH(ops::Rays(ctx, lens).fwd({cameras, ids, pixels, n}, rays),
                    doctest::Contains("needs the cameras' lens tables"));
}

namespace {

// Forward-facing cameras for NDC (a capture's world after LLFF's recentring: looking down −z from near the origin,
// the near plane at z = −1 ahead): the OPENCV and fisheye lenses and a pinhole of lens_cameras, and the OPENCV lens on
// images 2 and 1 pixels wide and high, where a pixel's neighbour pair is the padding pair or none.
LensBatch ndc_lens_batch() {
  LensBatch b;
  b.cameras = lens_cameras();
  for (size_t c = 0; c < b.cameras.size(); ++c) {
    rotate(b.cameras[c], 0.05 * (c + 1));
    b.cameras[c].camera_to_world[3] = 0.1 * c - 0.1;
    b.cameras[c].camera_to_world[7] = 0.05 * c;
    b.cameras[c].camera_to_world[11] = 0.02 * c;
  }
  for (uint32_t size : {2u, 1u}) {
    Camera small = b.cameras[0];
    small.width_px = size;
    small.height_px = 3 - size;
    small.center_x_px = 0.5 * size;
    small.center_y_px = 0.5 * (3 - size);
    small.focal_x_px = small.focal_y_px = 1.5;
    b.cameras.push_back(small);
  }
  b.tables = data::build_lens_tables(b.cameras);
  b.packed = pack_cameras(b.cameras);
  data::set_lens_table_slots(b.packed, b.tables);
  for (uint32_t c = 0; c < b.cameras.size(); ++c) {
    const uint32_t pixels = b.cameras[c].width_px * b.cameras[c].height_px;
    for (uint32_t p = 0; p < pixels; p += (pixels > 8 ? 13 : 1)) {
      b.camera_ids.push_back(c);
      b.pixel_ids.push_back(p);
    }
    for (uint32_t p : {b.cameras[c].width_px - 1, pixels - 1}) {  // the last column and row's pairs
      b.camera_ids.push_back(c);
      b.pixel_ids.push_back(p);
    }
  }
  return b;
}

}  // namespace

TEST_CASE("rays: behind a lens in NDC (cylinders), the kernel is the reference mirror, at the centre, offset and jittered") {
  const LensBatch b = ndc_lens_batch();
  std::vector<double> tables(b.tables.values.begin(), b.tables.values.end());
  for (bool jitter : {false, true}) {
    for (float offset : {0.5f, 0.0f}) {
      if (jitter && offset == 0.0f) continue;
      RaysOptions options;
      options.ray_shape = RayShape::cylinder;
      options.lens_tables = true;
      options.unit_viewdirs = false;
      options.jitter_subpixel = jitter;
      options.pixel_center_offset = offset;
      INFO("jitter " << jitter << ", offset " << offset);
      const RngKey key{5, 2, 40};
      const DeviceRays rays = run_device(options, b, key);
      std::vector<double> ro, rd, rv, rr, rn, rf, rl;
      ref::rays_fwd(options, test::to_double(b.packed), b.camera_ids, b.pixel_ids, ro, rd, rv, rr, rn, rf, rl,
                    b.camera_ids.size(), b.cameras.size(), key, tables);
      double worst_radius = 0.0;
      for (size_t k = 0; k < rd.size(); ++k) {
        // The NDC ray is a few float32 operations on entries of size ≤ 5 (a slope of ≤ 1.6 for these cameras, NDC
        // scales 2f/w ≤ 3): within 4e-6 of each value's size.
        REQUIRE(std::abs(rays.origins[k] - ro[k]) < 4e-6 * (1 + std::abs(ro[k])));
        REQUIRE(std::abs(rays.directions[k] - rd[k]) < 4e-6 * (1 + std::abs(rd[k])));
        REQUIRE(std::abs(rays.viewdirs[k] - rv[k]) < 1e-6 * (1 + std::abs(rv[k])));
      }
      for (size_t k = 0; k < rr.size(); ++k) {
        REQUIRE(std::isfinite(rays.radii[k]));
        REQUIRE(rr[k] > 0.0);
        worst_radius = std::max(worst_radius, std::abs(rays.radii[k] - rr[k]) / rr[k]);
      }
      // The radius differences two neighbouring float32 table entries (|u| ≤ 4, neighbours ~1/f ≥ 0.005 apart in the
      // 64-pixel cameras): an error of ~2^-24·4 / 0.005 ≈ 5e-5 relative at worst.
      MESSAGE("worst NDC radius " << worst_radius << " relative");
      CHECK(worst_radius < 1e-4);
    }
  }
}

TEST_CASE("rays: a lens without distortion in NDC gives the pinhole's NDC rays and radii") {
  // OPENCV with every coefficient 0 is a pinhole read through its table: the table's neighbour pairs must give the
  // pinhole formula's radius (its 1/f steps and padding pairs), in the reference and on the device.
  LensBatch lens = ndc_lens_batch();
  for (auto& cam : lens.cameras) cam.lens = {LensModel::opencv, 0, 0, 0, 0, 0, 0};
  lens.tables = data::build_lens_tables(lens.cameras);
  lens.packed = pack_cameras(lens.cameras);
  data::set_lens_table_slots(lens.packed, lens.tables);
  LensBatch pinhole = lens;
  for (auto& cam : pinhole.cameras) cam.lens = Lens{};
  pinhole.packed = pack_cameras(pinhole.cameras);
  std::vector<double> tables(lens.tables.values.begin(), lens.tables.values.end());
  for (float offset : {0.5f, 0.25f}) {
    RaysOptions options;
    options.ray_shape = RayShape::cylinder;
    options.pixel_center_offset = offset;
    RaysOptions with_tables = options;
    with_tables.lens_tables = true;
    INFO("offset " << offset);
    std::vector<double> lo, ld, lv, lr, ln, lf, ll, po, pd, pv, pr, pn, pf, pl;
    const size_t n = lens.camera_ids.size();
    ref::rays_fwd(with_tables, test::to_double(lens.packed), lens.camera_ids, lens.pixel_ids, lo, ld, lv, lr, ln, lf,
                  ll, n, lens.cameras.size(), {}, tables);
    ref::rays_fwd(options, test::to_double(pinhole.packed), pinhole.camera_ids, pinhole.pixel_ids, po, pd, pv, pr, pn,
                  pf, pl, n, pinhole.cameras.size(), {});
    const DeviceRays device = run_device(with_tables, lens, {});
    for (size_t k = 0; k < n; ++k) {
      const std::string where = "camera " + std::to_string(lens.camera_ids[k]) + ", pixel " +
                                std::to_string(lens.pixel_ids[k]);
      INFO(where);
      for (int a = 0; a < 3; ++a) REQUIRE(lo[3 * k + a] == doctest::Approx(po[3 * k + a]).epsilon(1e-6));
      // The table holds float32 (u, v): the reference's radius from them is the pinhole's to float32's rounding of
      // neighbour differences; the kernel's too.
      CHECK(lr[k] == doctest::Approx(pr[k]).epsilon(1e-4));
      CHECK(device.radii[k] == doctest::Approx(pr[k]).epsilon(1e-4));
    }
  }
}
