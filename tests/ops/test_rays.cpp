// Camera rays (kernels/rays.cl): cone and NDC rays against the reference (which differences neighbouring pixels
// literally, as the official code), cameras looking exactly along an axis, NDC rays nearly parallel to the near plane
// or starting on or behind it, pixel-centre offset, sub-pixel jitter and its reproducibility, view dependence off,
// raw (un-normalised) view directions, and invalid ids.
#include <doctest/doctest.h>

#include <array>

#include "core/camera.hpp"
#include "kernel_checks.hpp"
#include "ops/rays.hpp"
#include "ref/rays.hpp"
#include "support/test_context.hpp"

using namespace mipnerf;
using test::kUnitRoundoff;

namespace {

// A rotation from a random unit quaternion; `max_angle` < π limits it to a cone around the identity (forward-facing
// scenes look down −z, like the unrotated camera).
std::array<double, 9> random_rotation(std::mt19937& rng, double max_angle) {
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double axis[3] = {normal(rng), normal(rng), normal(rng)};
  const double len = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  const double angle = max_angle * unit(rng), s = std::sin(angle / 2);
  const double w = std::cos(angle / 2), x = axis[0] / len * s, y = axis[1] / len * s, z = axis[2] / len * s;
  return {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
          2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
          2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
}

struct Scene {
  std::vector<Camera> cameras;
  std::vector<uint32_t> camera_ids, pixel_ids;
};

// `forward_facing`: small rotations and origins near z = 0, so every ray crosses the NDC near plane z = −1 ahead.
Scene random_scene(size_t n_cameras, size_t n_rays, unsigned seed, bool forward_facing) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0), signed_unit(-1.0, 1.0);
  Scene s;
  for (size_t c = 0; c < n_cameras; ++c) {
    Camera cam;
    const auto rot = random_rotation(rng, forward_facing ? 0.3 : M_PI);
    const double spread = forward_facing ? 0.3 : 4.0;
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 3; ++col) cam.camera_to_world[row * 4 + col] = rot[row * 3 + col];
      cam.camera_to_world[row * 4 + 3] = spread * signed_unit(rng);
    }
    cam.width_px = 1 + static_cast<uint32_t>(800 * unit(rng));
    cam.height_px = 1 + static_cast<uint32_t>(800 * unit(rng));
    cam.focal_x_px = forward_facing ? 300 + 700 * unit(rng) : 50 + 1500 * unit(rng);
    cam.focal_y_px = cam.focal_x_px * (c % 3 == 0 ? 1.0 : 0.9 + 0.2 * unit(rng));  // some cameras with fx ≠ fy
    cam.center_x_px = 0.5 * cam.width_px + (c % 2 ? 0.0 : std::round(8 * signed_unit(rng)) / 2);
    cam.center_y_px = 0.5 * cam.height_px;
    cam.near = forward_facing ? 0.0 : 0.5 + unit(rng);
    cam.far = forward_facing ? 1.0 : 4.0 + 4 * unit(rng);
    cam.lossmult = std::pow(4.0, static_cast<int>(4 * unit(rng)));
    s.cameras.push_back(cam);
  }
  for (size_t i = 0; i < n_rays; ++i) {
    const uint32_t c = static_cast<uint32_t>(rng() % n_cameras);
    s.camera_ids.push_back(c);
    s.pixel_ids.push_back(static_cast<uint32_t>(rng() % (s.cameras[c].width_px * s.cameras[c].height_px)));
  }
  return s;
}

struct RayArrays {
  std::vector<float> origins, directions, viewdirs, radii, near, far, lossmult;
};

RayArrays run_device(const RaysOptions& options, const Scene& s, const RngKey& key = {}) {
  auto& ctx = test::test_context();
  const size_t n = s.camera_ids.size();
  const auto packed = pack_cameras(s.cameras);
  auto cameras = test::upload(ctx, packed, "cameras");
  auto camera_ids = test::upload(ctx, s.camera_ids, "camera_ids"),
       pixel_ids = test::upload(ctx, s.pixel_ids, "pixel_ids");
  auto rays = test::filled_rays(ctx, n, 7.0f);
  ops::Rays(ctx, options).fwd({cameras, camera_ids, pixel_ids, n}, rays, key);
  return {rays.origins.download(ctx), rays.directions.download(ctx), rays.viewdirs.download(ctx),
          rays.radii.download(ctx),   rays.near.download(ctx),       rays.far.download(ctx),
          rays.lossmult.download(ctx)};
}

struct RefArrays {
  std::vector<double> origins, directions, viewdirs, radii, near, far, lossmult;
};

RefArrays run_ref(const RaysOptions& options, const Scene& s, const RngKey& key = {}) {
  RefArrays r;
  const auto packed = test::to_double(pack_cameras(s.cameras));
  ref::rays_fwd(options, packed, s.camera_ids, s.pixel_ids, r.origins, r.directions, r.viewdirs, r.radii, r.near, r.far,
                r.lossmult, s.camera_ids.size(), s.cameras.size(), key);
  return r;
}

// Tolerance of a world direction component: the camera-frame direction ((p − c) + o)/f is ≤ 2 roundings and a
// 2.5-ulp division, the rotation 3 products and 2 sums of terms bounded by |dir_camera|: ≤ 8u·‖dir_camera‖₁ per
// component, twice that.
std::function<double(size_t)> direction_tolerance(const std::vector<double>& directions) {
  return [&directions](size_t i) {
    const size_t ray = i / 3;
    double norm1 = 0;
    for (int a = 0; a < 3; ++a) norm1 += std::abs(directions[3 * ray + a]);
    return 2 * 8 * kUnitRoundoff * norm1 * 1.8;  // ‖R·v‖₁ ≥ ‖v‖₁/√3 for a rotation: 1.8 > √3 converts the norms
  };
}

void check_cone_rays(const RaysOptions& options, const Scene& s, const RngKey& key = {}) {
  const auto dev = run_device(options, s, key);
  const auto r = run_ref(options, s, key);
  const auto exact = [](size_t) { return 0.0; };
  MIPNERF_CHECK_CLOSE("origins (copied)", dev.origins, r.origins, exact);
  MIPNERF_CHECK_CLOSE("near (copied)", dev.near, r.near, exact);
  MIPNERF_CHECK_CLOSE("far (copied)", dev.far, r.far, exact);
  MIPNERF_CHECK_CLOSE("lossmult (copied)", dev.lossmult, r.lossmult, exact);
  MIPNERF_CHECK_CLOSE("directions", dev.directions, r.directions, direction_tolerance(r.directions));
  // Unit view direction: the direction's error (above, relative to its norm) plus the norm (3 roundings, sqrt
  // ≤ 3 ulp) and the division (2.5 ulp): 16u·1.8 + 12u ≤ 48u absolute; twice that.
  MIPNERF_CHECK_CLOSE("viewdirs", dev.viewdirs, r.viewdirs, [](size_t) { return 2 * 48 * kUnitRoundoff; });
  // Radius |R column 0|/fx·(2/√12): three squares, two sums, sqrt ≤ 3 ulp, a division ≤ 2.5 ulp, a product:
  // ≤ 16u relative (the reference's literal neighbour difference in double is exact to 1e-12); twice that.
  MIPNERF_CHECK_CLOSE("radii", dev.radii, r.radii, [&](size_t i) { return 2 * 16 * kUnitRoundoff * r.radii[i]; });
}

// NDC rays of `s` against the reference, with the float32 bounds derived below.
void check_ndc_rays(const Scene& s) {
  RaysOptions options;
  options.ray_shape = RayShape::cylinder;
  const auto dev = run_device(options, s);
  const auto r = run_ref(options, s);
  // NDC origin (2f/(w·n))·o_near.x with o_near = o + t·d: t = −(n + o_z)/d_z, a few roundings of terms bounded by
  // |o| + |t·d|, then a product with 2f/w (≤ 2·1000/1 here): ≤ 10u·(2f/w)·(|o| + |t·d|) per component. The
  // NDC direction subtracts o_near/o_z from d/d_z likewise. The reference converts the float camera exactly.
  std::vector<double> origin_tol(r.origins.size()), direction_tol(r.directions.size());
  for (size_t i = 0; i < s.camera_ids.size(); ++i) {
    const auto& cam = s.cameras[s.camera_ids[i]];
    const Ray ray =
        camera_ray(cam, s.pixel_ids[i] % cam.width_px + 0.5, s.pixel_ids[i] / cam.width_px + 0.5);
    const double t = std::abs((1.0 + ray.origin_world[2]) / ray.direction_world[2]);
    for (int a = 0; a < 3; ++a) {
      const double scale = 2 * (a == 0 ? cam.focal_x_px / cam.width_px : cam.focal_y_px / cam.height_px);
      const double terms = std::abs(ray.origin_world[a]) + t * std::abs(ray.direction_world[a]);
      const double slope = std::abs(ray.direction_world[a] / ray.direction_world[2]);
      origin_tol[3 * i + a] = 2 * 10 * kUnitRoundoff * scale * (terms + 1);
      direction_tol[3 * i + a] = 2 * 10 * kUnitRoundoff * scale * (terms + slope + 1);
    }
  }
  MIPNERF_CHECK_CLOSE("NDC origins", dev.origins, r.origins, [&](size_t i) { return origin_tol[i]; });
  MIPNERF_CHECK_CLOSE("NDC directions", dev.directions, r.directions, [&](size_t i) { return direction_tol[i]; });
  // The radius, from the kernel's closed form of the neighbour differences (no cancellation): its terms are
  // ≤ 12 roundings of themselves; the reference subtracts neighbouring NDC origins in double (1e-12 relative).
  MIPNERF_CHECK_CLOSE("NDC radii", dev.radii, r.radii, [&](size_t i) { return 2 * 24 * kUnitRoundoff * r.radii[i]; });
  MIPNERF_CHECK_CLOSE("viewdirs", dev.viewdirs, r.viewdirs, [](size_t) { return 2 * 48 * kUnitRoundoff; });
  for (size_t i = 0; i < s.camera_ids.size(); ++i) {
    REQUIRE(dev.origins[3 * i + 2] == -1.0f);    // every NDC ray starts on the near plane z = −1 ...
    REQUIRE(dev.directions[3 * i + 2] == 2.0f);  // ... and reaches z = 1 (infinity) at t = 1
  }
}

}  // namespace

TEST_CASE("rays: cone rays match the CPU reference on 10,000 random pixels of 40 cameras") {
  const Scene s = random_scene(40, 10000, 51, false);
  check_cone_rays({}, s);
}

TEST_CASE("rays: the cone radius is the neighbouring-pixel distance times 2 over sqrt 12") {
  // An unrotated camera with fx = 500: neighbouring directions differ by exactly 1/500, so r = 1/(500·√3).
  Scene s;
  Camera cam;
  cam.focal_x_px = cam.focal_y_px = 500;
  cam.width_px = 400;
  cam.height_px = 300;
  cam.center_x_px = 200;
  cam.center_y_px = 150;
  s.cameras = {cam};
  s.camera_ids = {0, 0, 0};
  s.pixel_ids = {0, 399, 300 * 400 - 1};  // first pixel, last of a row, last pixel
  const auto dev = run_device({}, s);
  for (float r : dev.radii) CHECK(r == doctest::Approx(1.0 / (500.0 * std::sqrt(3.0))).epsilon(1e-6));
  // Pixel (0, 0) is sampled at its centre (0.5, 0.5): direction ((0.5 − 200)/500, −(0.5 − 150)/500, −1).
  CHECK(dev.directions[0] == doctest::Approx(-199.5 / 500).epsilon(1e-7));
  CHECK(dev.directions[1] == doctest::Approx(149.5 / 500).epsilon(1e-7));
  CHECK(dev.directions[2] == -1.0f);
}

TEST_CASE("rays: cameras looking exactly along an axis give exact axis rays at the principal point") {
  // Quarter and half turns: the camera looks down −z (identity), +z, ±x and ±y. With the principal point on a pixel
  // centre, that pixel's camera-frame direction is (0, −0, −1) and its world direction exactly the axis (products
  // with 0 and ±1, sums with 0); every pixel matches the reference within the cone-ray bounds. What the Gaussian and
  // encoding stages make of axis-aligned (and zero) directions is tested in test_gaussian.cpp and test_encode.cpp.
  const std::vector<std::array<double, 9>> rotations = {
      {1, 0, 0, 0, 1, 0, 0, 0, 1},  {-1, 0, 0, 0, 1, 0, 0, 0, -1}, {0, 0, 1, 0, 1, 0, -1, 0, 0},
      {0, 0, -1, 0, 1, 0, 1, 0, 0}, {1, 0, 0, 0, 0, 1, 0, -1, 0},  {1, 0, 0, 0, 0, -1, 0, 1, 0}};
  const double looks[6][3] = {{0, 0, -1}, {0, 0, 1}, {-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}};
  Scene s;
  const uint32_t size = 33;
  for (size_t c = 0; c < rotations.size(); ++c) {
    Camera cam;
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 3; ++col) cam.camera_to_world[row * 4 + col] = rotations[c][row * 3 + col];
      cam.camera_to_world[row * 4 + 3] = 0.5 * row - 0.25;
    }
    cam.width_px = cam.height_px = size;
    cam.focal_x_px = cam.focal_y_px = 40;
    cam.center_x_px = cam.center_y_px = 16.5;  // the centre of pixel (16, 16)
    s.cameras.push_back(cam);
    for (uint32_t p = 0; p < size * size; ++p) {
      s.camera_ids.push_back(static_cast<uint32_t>(c));
      s.pixel_ids.push_back(p);
    }
  }
  check_cone_rays({}, s);
  const auto dev = run_device({}, s);
  for (size_t c = 0; c < rotations.size(); ++c) {
    const size_t ray = c * size * size + 16 * size + 16;
    INFO("camera looking along (" << looks[c][0] << ", " << looks[c][1] << ", " << looks[c][2] << ")");
    for (int a = 0; a < 3; ++a) {
      CHECK(dev.directions[3 * ray + a] == static_cast<float>(looks[c][a]));
      CHECK(dev.viewdirs[3 * ray + a] == static_cast<float>(looks[c][a]));
    }
  }
}

TEST_CASE("rays: NDC cylinder rays for forward-facing scenes match the official conversion") {
  check_ndc_rays(random_scene(20, 10000, 52, true));
}

TEST_CASE("rays: NDC rays nearly parallel to the near plane, or from on or behind it, match the official conversion") {
  // Cameras whose arithmetic is exact in float32 (rotations by quarter turns, focal lengths powers of 2, principal
  // points on the half-pixel grid), so the world origin and direction the kernel converts are exactly the
  // reference's and every difference is the conversion's own rounding:
  //  - tilted a quarter turn about x or y: each pixel's direction has z = ±(p − c + 0.5)/f, down to 0.5/2^20 ≈ 5e-7
  //    (nearly parallel to the near plane z = −1), and with c on a pixel centre exactly 0 in one row or column;
  //  - unrotated with f = 2^-4 (a field of view of 179.6°): z = −1 but slopes d_x/d_z up to 248.
  // Origins at z = 0 and 0.25 (in front of the near plane), −1 (on it: the shift t is 0) and −1.5 (behind it: t < 0).
  // Where d_z = 0 the official conversion divides by 0 (Inf and NaN); the kernel and the reference convert such a
  // ray as if d_z were −1e-8 (kernels/rays.cl, NDC_MIN_DIR_Z): a finite ray far outside the NDC box.
  constexpr double kMinDirZ = 1e-8f;  // NDC_MIN_DIR_Z, as the float the kernel compares with
  Scene s;
  const std::array<double, 9> quarter_x = {1, 0, 0, 0, 0, -1, 0, 1, 0}, quarter_y = {0, 0, 1, 0, 1, 0, -1, 0, 0},
                              minus_quarter_x = {1, 0, 0, 0, 0, 1, 0, -1, 0}, identity = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  struct Setup {
    std::array<double, 9> rotation;
    double focal, center_offset;  // center = size/2 + offset (0.5: a pixel centre, where a direction z can be 0)
  };
  const std::vector<Setup> setups = {{quarter_x, 1.0, 0.0},          {quarter_x, 64.0, 0.5},
                                     {quarter_y, 4096.0, 0.0},       {minus_quarter_x, 1048576.0, 0.0},
                                     {quarter_y, 1048576.0, 0.5},    {identity, 0.0625, 0.0},
                                     {identity, 0.0625, 0.5}};
  const double origins_z[4] = {0.0, 0.25, -1.0, -1.5};
  const uint32_t size = 32;
  for (size_t c = 0; c < setups.size() * 4; ++c) {
    const Setup& setup = setups[c / 4];
    Camera cam;
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 3; ++col) cam.camera_to_world[row * 4 + col] = setup.rotation[row * 3 + col];
    }
    cam.camera_to_world[3] = c % 2 ? 0.125 : -0.375;
    cam.camera_to_world[7] = c % 3 ? 0.25 : -0.5;
    cam.camera_to_world[11] = origins_z[c % 4];
    cam.width_px = cam.height_px = size;
    cam.focal_x_px = cam.focal_y_px = setup.focal;
    cam.center_x_px = cam.center_y_px = size / 2 + setup.center_offset;
    cam.near = 0.0;
    cam.far = 1.0;
    s.cameras.push_back(cam);
    for (uint32_t p = 0; p < size * size; ++p) {
      s.camera_ids.push_back(static_cast<uint32_t>(c));
      s.pixel_ids.push_back(p);
    }
  }
  RaysOptions options;
  options.ray_shape = RayShape::cylinder;
  const auto dev = run_device(options, s);
  const auto r = run_ref(options, s);
  for (const auto* v : {&dev.origins, &dev.directions, &dev.viewdirs, &dev.radii}) REQUIRE(test::all_finite(*v));
  // Bounds, from the exact inputs (n = 1):
  //  - t = −(n + o_z)/d_z: a sum and a division (≤ 2.5 ulp): ≤ 6u relative. o_near = o + t·d: ≤ 8u·(|o_a| + |t·d_a|).
  //    Origin a·o_near/(−n) with a = 2f/w (≤ 5u, a division): ≤ 14u·a·(|o_a| + |t·d_a|).
  //  - Direction a·(o_a·d_z − o_z·d_a)/(n·d_z): two products and their difference ≤ 2u·(|o_a·d_z| + |o_z·d_a|),
  //    the division, a and the product ≤ 11u more: ≤ 14u·a·(|o_a| + |o_z·d_a/d_z|)/n.
  //  - Radius: the neighbour differences' closed form (n + o_z)/(z0·z1)·(s_a·z0 − d_a·(z1 − z0)) scaled by a, each
  //    term one product or none of two (no cancellation for these cameras: one of them is 0), then hypot (≤ 4 ulp),
  //    the mean and 2/√12: ≤ 28u relative.
  // The reference converts in double (the official formulas: its d/d_z − o_near/o_near_z cancels, but only to
  // ~1e-16 of the slope); the tolerances are twice the float32 bounds.
  std::vector<double> origin_tol(r.origins.size()), direction_tol(r.directions.size());
  size_t guarded = 0;
  for (size_t i = 0; i < s.camera_ids.size(); ++i) {
    const auto& cam = s.cameras[s.camera_ids[i]];
    const Ray ray = camera_ray(cam, s.pixel_ids[i] % size + 0.5, s.pixel_ids[i] / size + 0.5);
    double d_z = ray.direction_world[2];
    if (std::abs(d_z) < kMinDirZ) {
      d_z = d_z > 0 ? kMinDirZ : -kMinDirZ;
      ++guarded;
    }
    const double o_z = ray.origin_world[2], t = -(1.0 + o_z) / d_z;
    for (int a = 0; a < 2; ++a) {
      const double scale = 2 * (a == 0 ? cam.focal_x_px : cam.focal_y_px) / size;
      const double o = std::abs(ray.origin_world[a]), d = ray.direction_world[a];
      origin_tol[3 * i + a] = 2 * 14 * kUnitRoundoff * scale * (o + std::abs(t * d));
      direction_tol[3 * i + a] = 2 * 14 * kUnitRoundoff * scale * (o + std::abs(o_z * d / d_z));
    }
    // z: the kernel writes −1 and 2 exactly (checked below); the reference's 1 + 2n/o_near_z and −2n/o_near_z
    // carry its double rounding of o_near_z = o_z + t·d_z = −n, ~1e-16.
    origin_tol[3 * i + 2] = direction_tol[3 * i + 2] = 1e-12;
  }
  CHECK(guarded == 4 * 2 * size);  // two setups (× 4 origins) have a row or column of directions with z = 0
  MIPNERF_CHECK_CLOSE("NDC origins (hard cameras)", dev.origins, r.origins, [&](size_t i) { return origin_tol[i]; });
  MIPNERF_CHECK_CLOSE("NDC directions (hard cameras)", dev.directions, r.directions,
                      [&](size_t i) { return direction_tol[i]; });
  MIPNERF_CHECK_CLOSE("NDC radii (hard cameras)", dev.radii, r.radii,
                      [&](size_t i) { return 2 * 28 * kUnitRoundoff * r.radii[i]; });
  MIPNERF_CHECK_CLOSE("viewdirs (hard cameras)", dev.viewdirs, r.viewdirs,
                      [](size_t) { return 2 * 48 * kUnitRoundoff; });
  for (size_t i = 0; i < s.camera_ids.size(); ++i) {
    REQUIRE(dev.origins[3 * i + 2] == -1.0f);
    REQUIRE(dev.directions[3 * i + 2] == 2.0f);
  }
}

TEST_CASE("rays: NDC rays of random forward-facing cameras on and behind the near plane match the official one") {
  // The forward-facing scenes of the test above with every origin moved to z = −1 (on the near plane: t = 0) or
  // into z ∈ [−3, −1) (behind it: t < 0, the ray is shifted back to the plane). Same bounds as there.
  Scene s = random_scene(20, 10000, 57, true);
  std::mt19937 rng(58);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (size_t c = 0; c < s.cameras.size(); ++c) s.cameras[c].camera_to_world[11] = c % 2 ? -1.0 : -1.0 - 2 * unit(rng);
  check_ndc_rays(s);
}

TEST_CASE("rays: pixel-centre offset 0 and sub-pixel jitter match the reference") {
  const Scene s = random_scene(10, 10000, 53, false);
  RaysOptions corners;
  corners.pixel_center_offset = 0.0f;  // original NeRF's convention
  check_cone_rays(corners, s);
  RaysOptions jitter;
  jitter.jitter_subpixel = true;
  check_cone_rays(jitter, s, {12345, 7, 1000});
}

TEST_CASE("rays: jittered positions stay inside their pixel and depend only on seed, step and ray") {
  // An unrotated camera at the origin: the image position is recovered exactly as x = d_x·fx + cx.
  Scene s;
  Camera cam;
  cam.focal_x_px = cam.focal_y_px = 100;
  cam.width_px = 64;
  cam.height_px = 48;
  cam.center_x_px = 32;
  cam.center_y_px = 24;
  s.cameras = {cam};
  for (uint32_t i = 0; i < 3000; ++i) {
    s.camera_ids.push_back(0);
    s.pixel_ids.push_back(i % (64 * 48));
  }
  RaysOptions options;
  options.jitter_subpixel = true;
  const RngKey key{99, 5, 0};
  const auto a = run_device(options, s, key);
  double min_offset = 1, max_offset = 0;
  for (size_t i = 0; i < s.pixel_ids.size(); ++i) {
    const double x = a.directions[3 * i] * 100.0 + 32.0, y = -a.directions[3 * i + 1] * 100.0 + 24.0;
    const double ox = x - s.pixel_ids[i] % 64, oy = y - s.pixel_ids[i] / 64;
    // Inside the pixel, up to the float rounding of the direction (1e-5 px).
    REQUIRE(ox > -1e-5);
    REQUIRE(ox < 1 + 1e-5);
    REQUIRE(oy > -1e-5);
    REQUIRE(oy < 1 + 1e-5);
    min_offset = std::min({min_offset, ox, oy});
    max_offset = std::max({max_offset, ox, oy});
  }
  CHECK(min_offset < 0.01);  // 3000 pairs of uniforms cover the pixel
  CHECK(max_offset > 0.99);
  // The same key gives the same rays; another step gives others.
  CHECK(run_device(options, s, key).directions == a.directions);
  CHECK(run_device(options, s, {99, 6, 0}).directions != a.directions);
  // Chunking: rays 1000.. launched on their own with first_ray = 1000 are the same rays.
  Scene tail = s;
  tail.camera_ids.erase(tail.camera_ids.begin(), tail.camera_ids.begin() + 1000);
  tail.pixel_ids.erase(tail.pixel_ids.begin(), tail.pixel_ids.begin() + 1000);
  const auto b = run_device(options, tail, {99, 5, 1000});
  CHECK(std::vector<float>(a.directions.begin() + 3000, a.directions.end()) == b.directions);
}

TEST_CASE("rays: raw view directions (UNIT_VIEWDIRS off) are the world directions, for cone and NDC rays") {
  // The official forward-facing LLFF loader passes viewdirs = the world directions before NDC (datasets.py,
  // LLFF._generate_rays). For cone rays those are `directions` themselves, bit for bit; for NDC rays the world
  // direction the kernel converts, held to the cone directions' bound against the reference. Nothing else changes.
  RaysOptions raw;
  raw.unit_viewdirs = false;
  const Scene cones = random_scene(20, 5000, 59, false);
  const auto cone = run_device(raw, cones);
  CHECK(cone.viewdirs == cone.directions);
  const auto cone_ref = run_ref(raw, cones);
  MIPNERF_CHECK_CLOSE("raw viewdirs (cone)", cone.viewdirs, cone_ref.viewdirs, direction_tolerance(cone_ref.viewdirs));
  const auto cone_unit = run_device({}, cones);
  CHECK(cone_unit.directions == cone.directions);
  CHECK(cone_unit.radii == cone.radii);

  raw.ray_shape = RayShape::cylinder;
  RaysOptions unit_ndc;
  unit_ndc.ray_shape = RayShape::cylinder;
  const Scene forward = random_scene(20, 5000, 60, true);
  const auto ndc = run_device(raw, forward);
  const auto ndc_ref = run_ref(raw, forward);
  MIPNERF_CHECK_CLOSE("raw viewdirs (NDC rays)", ndc.viewdirs, ndc_ref.viewdirs, direction_tolerance(ndc_ref.viewdirs));
  const auto ndc_unit = run_device(unit_ndc, forward);
  CHECK(ndc_unit.origins == ndc.origins);
  CHECK(ndc_unit.directions == ndc.directions);
  CHECK(ndc_unit.radii == ndc.radii);
  // The camera-frame direction has z = −1, so a raw view direction is at least as long as a unit one: the two
  // specialisations differ (by the pixel's 1/cos of its angle to the optical axis) and the reference says which.
  const auto unit_ref = run_ref(unit_ndc, forward);
  for (size_t i = 0; i < forward.camera_ids.size(); ++i) {
    const double* v = ndc_ref.viewdirs.data() + 3 * i;
    const double norm = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    REQUIRE(norm >= 1.0 - 1e-6);  // 1, up to the float32 rounding of the rotation
    for (int a = 0; a < 3; ++a) REQUIRE(std::abs(v[a] / norm - unit_ref.viewdirs[3 * i + a]) <= 1e-12);
  }
}

TEST_CASE("rays: without view dependence the viewdirs buffer is never written") {
  const Scene s = random_scene(5, 1000, 54, false);
  RaysOptions options;
  options.view_dependence = false;
  const auto dev = run_device(options, s);
  for (float v : dev.viewdirs) REQUIRE(v == 7.0f);  // the sentinel run_device filled it with
  const auto with = run_device({}, s);
  CHECK(dev.directions == with.directions);
  CHECK(dev.radii == with.radii);
}

TEST_CASE("rays: an unknown camera or a pixel outside the image gives NaN, not a wrong ray") {
  Scene s = random_scene(3, 4, 55, false);
  s.camera_ids[1] = 3;  // one past the last camera
  s.pixel_ids[2] = s.cameras[s.camera_ids[2]].width_px * s.cameras[s.camera_ids[2]].height_px;
  const auto dev = run_device({}, s);
  for (size_t i : {size_t(1), size_t(2)}) {
    CHECK(std::isnan(dev.origins[3 * i]));
    CHECK(std::isnan(dev.directions[3 * i + 2]));
    CHECK(std::isnan(dev.radii[i]));
    CHECK(std::isnan(dev.near[i]));
  }
  for (size_t i : {size_t(0), size_t(3)}) CHECK(std::isfinite(dev.radii[i]));
  // A cameras buffer that is not whole cameras is refused before the launch.
  auto& ctx = test::test_context();
  ocl::DeviceArray<float> cameras(ctx, 25, "cameras [25]");
  ocl::DeviceArray<uint32_t> ids(ctx, 4, "ids");
  ops::RayBundle out(ctx, 4);
  ops::Rays rays(ctx, {});
  CHECK_THROWS_WITH_AS(rays.fwd({cameras, ids, ids, 4}, out),
                       doctest::Contains("cameras [25]"), Error);
}

TEST_CASE("rays: with the run's NDC map, a camera of another field of view lands in the NDC the run trained in") {
  // Camera A (the capture's: f = 10 on 16×12) and camera B at the same pose with twice its focal length (a 2× zoom).
  // With pixel centres at offset 0, B's pixel (2x − 8, 2y − 6) looks along A's pixel (x, y). Mapped with A's NDC map
  // (RaysOptions::ndc_scale, what an NDC run records), B's ray is A's ray in NDC; with its own map it is elsewhere.
  Scene s;
  Camera a;
  a.width_px = 16;
  a.height_px = 12;
  a.focal_x_px = a.focal_y_px = 10.0;
  a.center_x_px = 8.0;
  a.center_y_px = 6.0;
  a.camera_to_world = {0.96, 0.0, 0.28, 0.1, 0.0, 1.0, 0.0, -0.2, -0.28, 0.0, 0.96, 0.05};
  a.near = 0.0;
  a.far = 1.0;
  Camera b = a;
  b.focal_x_px = b.focal_y_px = 20.0;
  s.cameras = {a, b};
  for (uint32_t y = 3; y < 9; ++y) {
    for (uint32_t x = 4; x < 12; ++x) {
      s.camera_ids.insert(s.camera_ids.end(), {0, 1});
      s.pixel_ids.insert(s.pixel_ids.end(), {y * 16 + x, (2 * y - 6) * 16 + (2 * x - 8)});
    }
  }
  RaysOptions options;
  options.ray_shape = RayShape::cylinder;
  options.pixel_center_offset = 0.0f;
  RaysOptions with_map = options;
  with_map.ndc_scale_x = 2.0f * 10.0f / 16.0f;
  with_map.ndc_scale_y = 2.0f * 10.0f / 12.0f;
  const RayArrays own = run_device(options, s), mapped = run_device(with_map, s);
  const RefArrays mapped_ref = run_ref(with_map, s);
  double worst_mapped = 0.0, smallest_own = 1e300;
  for (size_t i = 0; i < s.camera_ids.size(); i += 2) {
    double own_difference = 0.0;
    for (int k = 0; k < 3; ++k) {
      worst_mapped =
          std::max({worst_mapped, static_cast<double>(std::abs(mapped.origins[3 * (i + 1) + k] - mapped.origins[3 * i + k])),
                    static_cast<double>(std::abs(mapped.directions[3 * (i + 1) + k] - mapped.directions[3 * i + k]))});
      own_difference =
          std::max(own_difference, static_cast<double>(std::abs(own.origins[3 * (i + 1) + k] - own.origins[3 * i + k])));
      // The device with the map is the reference with it.
      REQUIRE(mapped.origins[3 * i + k] == doctest::Approx(mapped_ref.origins[3 * i + k]).epsilon(1e-6));
      REQUIRE(mapped.origins[3 * (i + 1) + k] == doctest::Approx(mapped_ref.origins[3 * (i + 1) + k]).epsilon(1e-6));
    }
    if (std::abs(own.origins[3 * i]) > 0.05) smallest_own = std::min(smallest_own, own_difference);
  }
  MESSAGE("B against A in NDC: with the run's map " << worst_mapped << ", each with its own at least " << smallest_own);
  CHECK(worst_mapped < 1e-5);
  CHECK(smallest_own > 0.01);
  // A's rays are the same with the map as with its own (its map is its own): bit for bit.
  for (size_t i = 0; i < s.camera_ids.size(); i += 2) {
    for (int k = 0; k < 3; ++k) {
      CHECK(mapped.origins[3 * i + k] == own.origins[3 * i + k]);
      CHECK(mapped.directions[3 * i + k] == own.directions[3 * i + k]);
    }
    CHECK(mapped.radii[i] == own.radii[i]);
  }
}
