// CPU reference of kernels/rays.cl.
#include "ref/rays.hpp"

#include <array>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/camera.hpp"
#include "core/rng.hpp"

namespace mipnerf::ref {
namespace {

constexpr double kRadiusPerPixelWidth = 0.57735026918962576451;  // 2/√12

Camera unpack_camera(const std::vector<double>& cameras, size_t id) {
  namespace L = camera_layout;
  const double* p = cameras.data() + id * L::stride;
  Camera cam;
  for (int k = 0; k < 12; ++k) cam.camera_to_world[k] = p[L::camera_to_world + k];
  cam.focal_x_px = p[L::focal_x];
  cam.focal_y_px = p[L::focal_y];
  cam.center_x_px = p[L::center_x];
  cam.center_y_px = p[L::center_y];
  cam.width_px = static_cast<uint32_t>(p[L::width]);
  cam.height_px = static_cast<uint32_t>(p[L::height]);
  cam.near = p[L::near];
  cam.far = p[L::far];
  cam.lossmult = p[L::lossmult];
  return cam;
}

double distance3(const double a[3], const double b[3]) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

struct RayOut {
  double origin[3], direction[3], viewdir[3], radius;
};

RayOut cone_ray(const Camera& cam, double x, double y, uint32_t px) {
  const Ray ray = camera_ray(cam, x, y);
  // The horizontal neighbour: the next pixel, the previous one in the last column (as official's edge padding).
  const double step = px + 1 < cam.width_px ? 1.0 : -1.0;
  const Ray neighbour = camera_ray(cam, x + step, y);
  RayOut out;
  for (int a = 0; a < 3; ++a) {
    out.origin[a] = ray.origin_world[a];
    out.direction[a] = ray.direction_world[a];
  }
  out.radius = distance3(ray.direction_world.data(), neighbour.direction_world.data()) * kRadiusPerPixelWidth;
  return out;
}

// Where the pair of neighbouring pixels that sets pixel p's NDC radius starts, relative to p: p itself, but in the
// last column / row the official code's padding pair (google/mipnerf LLFF._generate_rays, dx[:, -2:-1]: pixels
// size − 3 and size − 2); a 2-pixel axis has only (0, 1), a 1-pixel axis looks one pixel outside.
double pair_start_shift(uint32_t p, uint32_t size) {
  if (p + 1 < size) return 0.0;
  return size >= 3 ? -2.0 : -1.0;
}

// The focal lengths NDC maps a camera with: those of options.ndc_scale (2f/size, the run's map) when given, else its own.
std::array<double, 2> ndc_focal_of(const Camera& cam, const RaysOptions& options) {
  if (options.ndc_scale_x > 0.0f && options.ndc_scale_y > 0.0f) {
    return {0.5 * options.ndc_scale_x * cam.width_px, 0.5 * options.ndc_scale_y * cam.height_px};
  }
  return {cam.focal_x_px, cam.focal_y_px};
}

RayOut ndc_ray(const Camera& cam, double x, double y, uint32_t px, uint32_t py, double near_plane,
               const std::array<double, 2>& ndc_focal) {
  const auto ndc_origin = [&](double xx, double yy, double o_ndc[3], double d_ndc[3]) {
    const Ray r = camera_ray(cam, xx, yy);
    convert_to_ndc(r.origin_world.data(), r.direction_world.data(), ndc_focal[0], ndc_focal[1], cam.width_px,
                   cam.height_px, near_plane, o_ndc, d_ndc);
  };
  RayOut out;
  ndc_origin(x, y, out.origin, out.direction);
  // The mean distance between the NDC origins of a pair of neighbours across and down: the pixel and the next, or
  // in the last column / row the pair the official code repeats there (pair_start_shift).
  const double shift_x = pair_start_shift(px, cam.width_px), shift_y = pair_start_shift(py, cam.height_px);
  double h0[3], h1[3], v0[3], v1[3], unused[3];
  ndc_origin(x + shift_x, y, h0, unused);
  ndc_origin(x + shift_x + 1.0, y, h1, unused);
  ndc_origin(x, y + shift_y, v0, unused);
  ndc_origin(x, y + shift_y + 1.0, v1, unused);
  out.radius = 0.5 * (distance3(h0, h1) + distance3(v0, v1)) * kRadiusPerPixelWidth;
  return out;
}

// Mirror of the kernel's lens_point: camera `id`'s lens table slot (the bits of the packed float, 0: a pinhole), and
// behind a lens the normalised (u, v) of (px + offset_x, py + offset_y) and the radius at unit depth, read from the
// table at the pixel centre and moved first order along the differences to the next entry across and down.
uint32_t lens_table_slot(const std::vector<double>& cameras, size_t id) {
  const float packed = static_cast<float>(cameras[id * camera_layout::stride + camera_layout::lens_table]);
  uint32_t slot;
  std::memcpy(&slot, &packed, sizeof slot);
  return slot;
}

struct LensPoint {
  double u, v, radius;
};

LensPoint lens_point(const std::vector<double>& tables, size_t first, const Camera& cam, uint32_t px, uint32_t py,
                     double offset_x, double offset_y) {
  const uint32_t w = cam.width_px, h = cam.height_px;
  auto entry = [&](uint32_t x, uint32_t y, int k) { return tables[4 * (first + static_cast<size_t>(y) * w + x) + k]; };
  LensPoint p{entry(px, py, 0), entry(px, py, 1), entry(px, py, 2)};
  for (int k = 0; k < 2; ++k) {
    // An axis one pixel long: a step of 1/f along it (the kernel's, and the table radius's, choice).
    const double across = w < 2 ? (k == 0 ? 1.0 / cam.focal_x_px : 0.0)
                          : px + 1 < w ? entry(px + 1, py, k) - entry(px, py, k)
                                       : entry(px, py, k) - entry(px - 1, py, k);
    const double down = h < 2 ? (k == 1 ? 1.0 / cam.focal_y_px : 0.0)
                        : py + 1 < h ? entry(px, py + 1, k) - entry(px, py, k)
                                     : entry(px, py, k) - entry(px, py - 1, k);
    (k == 0 ? p.u : p.v) += (offset_x - 0.5) * across + (offset_y - 0.5) * down;
  }
  return p;
}

// A cone ray behind a lens: direction camera_to_world·(u, −v, −1), radius |column 0|·(table radius).
RayOut lens_cone_ray(const Camera& cam, const LensPoint& p) {
  const auto& m = cam.camera_to_world;
  const double d_camera[3] = {p.u, -p.v, -1.0};
  RayOut out;
  for (int a = 0; a < 3; ++a) {
    out.origin[a] = m[4 * a + 3];
    out.direction[a] = m[4 * a] * d_camera[0] + m[4 * a + 1] * d_camera[1] + m[4 * a + 2] * d_camera[2];
  }
  out.radius = std::sqrt(m[0] * m[0] + m[4] * m[4] + m[8] * m[8]) * p.radius;
  return out;
}

// A lens ray in NDC (a forward-facing capture behind a lens): the lens ray of lens_cone_ray converted as a pinhole's,
// and, literally as ndc_ray's, the mean distance between the NDC origins of the pair of neighbours across and down
// (pair_start_shift's pairs), each neighbour's ray read from the table at the same offset. On an axis one pixel long
// the pair is the pinhole's: the point 1/f back along that axis, and the pixel.
RayOut lens_ndc_ray(const Camera& cam, const std::vector<double>& tables, size_t first, uint32_t px, uint32_t py,
                    double offset_x, double offset_y, double near_plane, const std::array<double, 2>& ndc_focal) {
  const auto& m = cam.camera_to_world;
  const double o[3] = {m[3], m[7], m[11]};
  const auto ndc_origin = [&](double u, double v, double o_ndc[3], double d_ndc[3]) {
    const double d_camera[3] = {u, -v, -1.0};
    double d[3];
    for (int a = 0; a < 3; ++a) d[a] = m[4 * a] * d_camera[0] + m[4 * a + 1] * d_camera[1] + m[4 * a + 2] * d_camera[2];
    convert_to_ndc(o, d, ndc_focal[0], ndc_focal[1], cam.width_px, cam.height_px, near_plane, o_ndc, d_ndc);
  };
  const LensPoint here = lens_point(tables, first, cam, px, py, offset_x, offset_y);
  RayOut out;
  ndc_origin(here.u, here.v, out.origin, out.direction);
  double unused[3], a[3], b[3];
  double distance[2];
  for (int axis = 0; axis < 2; ++axis) {
    const uint32_t p = axis == 0 ? px : py, size = axis == 0 ? cam.width_px : cam.height_px;
    if (size < 2) {
      const double back_u = axis == 0 ? 1.0 / cam.focal_x_px : 0.0, back_v = axis == 1 ? 1.0 / cam.focal_y_px : 0.0;
      ndc_origin(here.u - back_u, here.v - back_v, a, unused);
      ndc_origin(here.u, here.v, b, unused);
    } else {
      const uint32_t start = static_cast<uint32_t>(static_cast<int64_t>(p) + static_cast<int64_t>(pair_start_shift(p, size)));
      const LensPoint p0 = axis == 0 ? lens_point(tables, first, cam, start, py, offset_x, offset_y)
                                     : lens_point(tables, first, cam, px, start, offset_x, offset_y);
      const LensPoint p1 = axis == 0 ? lens_point(tables, first, cam, start + 1, py, offset_x, offset_y)
                                     : lens_point(tables, first, cam, px, start + 1, offset_x, offset_y);
      ndc_origin(p0.u, p0.v, a, unused);
      ndc_origin(p1.u, p1.v, b, unused);
    }
    distance[axis] = distance3(a, b);
  }
  out.radius = 0.5 * (distance[0] + distance[1]) * kRadiusPerPixelWidth;
  return out;
}

}  // namespace

void convert_to_ndc(const double o[3], const double d[3], double focal_x, double focal_y, double width, double height,
                    double near_plane, double o_ndc[3], double d_ndc[3]) {
  // The kernel's guard (kernels/rays.cl ndc_direction_z): d_z within 1e-8 of 0, a ray (nearly) parallel to the near
  // plane, converts as if d_z were +1e-8 (d_z > 0) or −1e-8 (d_z < 0 or ±0), 1e-8 as the float the kernel compares
  // with, where the official code divides by d_z = 0 and returns Inf and NaN. Otherwise the official formulas.
  constexpr double min_dir_z = 1e-8f;
  const double d_z = std::abs(d[2]) < min_dir_z ? (d[2] > 0 ? min_dir_z : -min_dir_z) : d[2];
  const double t = -(near_plane + o[2]) / d_z;
  const double o_near[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d_z};
  const double ax = -2.0 * focal_x / width, ay = -2.0 * focal_y / height;
  o_ndc[0] = ax * o_near[0] / o_near[2];
  o_ndc[1] = ay * o_near[1] / o_near[2];
  o_ndc[2] = 1.0 + 2.0 * near_plane / o_near[2];
  d_ndc[0] = ax * (d[0] / d_z - o_near[0] / o_near[2]);
  d_ndc[1] = ay * (d[1] / d_z - o_near[1] / o_near[2]);
  d_ndc[2] = -2.0 * near_plane / o_near[2];
}

void rays_fwd(const RaysOptions& options, const std::vector<double>& cameras,
              const std::vector<uint32_t>& camera_ids, const std::vector<uint32_t>& pixel_ids,
              std::vector<double>& origins, std::vector<double>& directions, std::vector<double>& viewdirs,
              std::vector<double>& radii, std::vector<double>& near, std::vector<double>& far,
              std::vector<double>& lossmult, size_t n_rays, size_t n_cameras, const RngKey& key,
              const std::vector<double>& lens_tables) {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  origins.assign(3 * n_rays, nan);
  directions.assign(3 * n_rays, nan);
  viewdirs.assign(3 * n_rays, nan);
  radii.assign(n_rays, nan);
  near.assign(n_rays, nan);
  far.assign(n_rays, nan);
  lossmult.assign(n_rays, nan);
  for (size_t i = 0; i < n_rays; ++i) {
    if (camera_ids[i] >= n_cameras) continue;
    const Camera cam = unpack_camera(cameras, camera_ids[i]);
    if (cam.width_px == 0 || pixel_ids[i] / cam.width_px >= cam.height_px) continue;
    const uint32_t px = pixel_ids[i] % cam.width_px, py = pixel_ids[i] / cam.width_px;
    double offset_x = options.pixel_center_offset, offset_y = options.pixel_center_offset;
    if (options.jitter_subpixel) {
      const auto xi =
          rng_uniform4(key.seed, key.first_ray + static_cast<uint32_t>(i), key.step, 0, rng_stream_subpixel);
      offset_x = xi[0];
      offset_y = xi[1];
    }
    const double x = px + offset_x, y = py + offset_y;
    const uint32_t lens_slot = options.lens_tables ? lens_table_slot(cameras, camera_ids[i]) : 0;
    RayOut ray;
    std::array<double, 3> world_direction;  // viewdirs: the world direction (in NDC scenes too)
    if (lens_slot != 0) {
      const RayOut lens_ray = lens_cone_ray(cam, lens_point(lens_tables, lens_slot - 1, cam, px, py, offset_x, offset_y));
      world_direction = {lens_ray.direction[0], lens_ray.direction[1], lens_ray.direction[2]};
      ray = options.ray_shape == RayShape::cylinder
                ? lens_ndc_ray(cam, lens_tables, lens_slot - 1, px, py, offset_x, offset_y, options.ndc_near_plane,
                               ndc_focal_of(cam, options))
                : lens_ray;
    } else {
      ray = options.ray_shape == RayShape::cylinder ? ndc_ray(cam, x, y, px, py, options.ndc_near_plane, ndc_focal_of(cam, options))
                                                    : cone_ray(cam, x, y, px);
      world_direction = camera_ray(cam, x, y).direction_world;  // `directions` holds the NDC one for cylinders
    }
    // Normalised unless options.unit_viewdirs is off (official forward-facing LLFF).
    const double norm = !options.unit_viewdirs ? 1.0
                                               : std::sqrt(world_direction[0] * world_direction[0] +
                                                           world_direction[1] * world_direction[1] +
                                                           world_direction[2] * world_direction[2]);
    for (int a = 0; a < 3; ++a) {
      origins[3 * i + a] = ray.origin[a];
      directions[3 * i + a] = ray.direction[a];
      viewdirs[3 * i + a] = world_direction[a] / norm;
    }
    radii[i] = ray.radius;
    near[i] = cam.near;
    far[i] = cam.far;
    lossmult[i] = cam.lossmult;
  }
}

}  // namespace mipnerf::ref
