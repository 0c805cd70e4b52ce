// Camera rays (stage 1): for each (camera, pixel) of a batch its origin, direction, unit view direction, cone
// radius, sampling range and loss weight. Cameras are packed [C][CAMERA_STRIDE] (common.cl, host/data/camera.hpp).
//
// Conventions (official mip-NeRF datasets.py; host/data/camera.hpp's camera_ray is the same math in double):
//  - Blender/OpenGL axes: the camera looks down −z_camera, y_camera is up; camera_to_world is Blender's
//    transform_matrix. pixel_ids[i] = y·width + x, y counted from the top row.
//  - Pixel (x, y) is sampled at image position (x + PIXEL_CENTER_OFFSET, y + PIXEL_CENTER_OFFSET) (official
//    and paper: 0.5, the pixel centre; original NeRF: 0), or with SUBPIXEL_JITTER at (x + ξ0, y + ξ1), ξ uniform
//    in [0, 1) from rng_uniform4(seed, first_ray + i, step, 0, RNG_STREAM_SUBPIXEL) (supersampling baselines).
//  - Camera-frame direction ((px − cx)/fx, −(py − cy)/fy, −1): not normalised, so t is depth along the optical
//    axis and near/far are depths. `viewdirs` is the unit world direction (official Blender and spherified LLFF), or
//    without UNIT_VIEWDIRS the world direction as it is (official forward-facing LLFF, whose loader passes
//    viewdirs = rays.directions, taken before the NDC conversion): in NDC scenes too, a world direction.
//  - Cone radius at t = 1 (RAY_SHAPE_CONE): the distance between the directions of horizontally neighbouring
//    pixels, times 2/√12, so the cone's disc has the per-axis variance r²/4 = w²/12 of the pixel's square
//    footprint of width w (paper §3.1). Those directions differ by camera_to_world·(1/fx, 0, 0) whatever the
//    pixel, so the distance is |column 0 of the rotation|/fx, computed without subtracting two nearby vectors.
//    (The official code differences the array along its first image axis, i.e. vertical neighbours, |col 1|/fy,
//    despite its comment; the two agree whenever fx = fy, as in every dataset it loads.)
//  - RAY_SHAPE_CYLINDER: forward-facing scenes in normalised device coordinates (official LLFF, convert_to_ndc
//    with near plane NDC_NEAR_PLANE = 1): origin and direction are the NDC ray, t ∈ [0, 1] spans the near plane
//    to infinity, and the radius is the mean of the distances from the pixel's NDC origin to its horizontal and
//    vertical neighbours' (the next pixel; the previous one in the last column/row, as official), times 2/√12.
//    The dataset packs near = 0, far = 1 for these scenes; this kernel copies near/far from the camera either way.
//    Origins on the near plane (t = 0) or behind it (t < 0) convert as officially; a direction parallel to the near
//    plane (d_z = 0, where the official conversion gives Inf and NaN) converts as if d_z were ±NDC_MIN_DIR_Z
//    (ndc_direction_z): a finite ray outside the NDC box.
//  - LENS_TABLES: a camera behind a lens (cam[CAMERA_LENS_TABLE] ≠ 0) takes each pixel centre's undistorted
//    normalised (u, v) and its cone radius at unit depth from its lens table (host/data/lens_tables.hpp: COLMAP's
//    models inverted by Newton's method in double precision, once per camera; the radius from the pixel's own
//    footprint, the mean distance to its undistorted neighbours × 2/√12). The direction is (u, −v, −1) rotated, and
//    the radius scales by |column 0| as the pinhole's does. A point off the centre (PIXEL_CENTER_OFFSET ≠ 0.5,
//    SUBPIXEL_JITTER) moves along the table's differences to the next pixel across and down: first order in the
//    offset, exact at the centre (tests/ops/test_rays_lens.cpp: 0.003 px off for a 0.4 px offset behind an OPENCV
//    lens, 0.17 px at the rim of a fisheye at 83°). With RAY_SHAPE_CYLINDER (a forward-facing capture behind a lens,
//    in NDC) the lens ray converts to NDC as a pinhole's does, and the radius is the mean NDC distance of the pairs
//    of neighbouring table entries across and down (lens_ndc_pairs): the pairs the pinhole formula uses, each
//    pixel's own undistorted position instead of a step of 1/f.
//  - Invalid input (camera id ≥ n_cameras, pixel id ≥ width·height) gives NaN in every output of that ray, so
//    it cannot pass unnoticed downstream.

#ifndef MIPNERF_RAYS_CL
#define MIPNERF_RAYS_CL

#define RAY_SHAPE_CONE 0
#define RAY_SHAPE_CYLINDER 1
#ifndef RAY_SHAPE
#define RAY_SHAPE RAY_SHAPE_CONE
#endif
#ifndef PIXEL_CENTER_OFFSET
#define PIXEL_CENTER_OFFSET 0.5f
#endif
#ifndef SUBPIXEL_JITTER
#define SUBPIXEL_JITTER 0
#endif
#ifndef VIEW_DEPENDENCE
#define VIEW_DEPENDENCE 1
#endif
#ifndef UNIT_VIEWDIRS
#define UNIT_VIEWDIRS 1
#endif
#ifndef NDC_NEAR_PLANE
#define NDC_NEAR_PLANE 1.0f
#endif
#ifndef LENS_TABLES
#define LENS_TABLES 0
#endif
#ifndef NDC_MIN_DIR_Z
#define NDC_MIN_DIR_Z 1e-8f
#endif

#define RADIUS_PER_PIXEL_WIDTH 0.577350269189625764f /* 2/√12 = 1/√3 */

// camera_to_world's rotation applied to a camera-frame vector.
inline float3 camera_rotate(__global const float* cam, float3 v) {
  __global const float* m = cam + CAMERA_TO_WORLD;
  return (float3)(m[0] * v.x + m[1] * v.y + m[2] * v.z, m[4] * v.x + m[5] * v.y + m[6] * v.z,
                  m[8] * v.x + m[9] * v.y + m[10] * v.z);
}

inline float3 camera_origin(__global const float* cam) {
  return (float3)(cam[CAMERA_TO_WORLD + 3], cam[CAMERA_TO_WORLD + 7], cam[CAMERA_TO_WORLD + 11]);
}

// Guard: a direction's z as the NDC conversion uses it, at least NDC_MIN_DIR_Z away from 0: +NDC_MIN_DIR_Z for a
// tiny positive z, −NDC_MIN_DIR_Z for a tiny negative one and for ±0 (towards the scene, which forward-facing
// cameras look at down −z; not by the sign of a zero, which depends on how the rotation's sums ran). NaN passes
// through. A ray parallel to the near plane (d_z = 0) never reaches it: the official convert_to_ndc divides by d_z
// and gives ±Inf and NaN origins, directions and radii. Converted as if tilted by 1e-8, it is a finite ray far
// outside the NDC box [−1, 1]³ (its origin ~(n + o_z)·|d|/1e-8 away), which samples only empty space. The
// camera-frame direction has z = −1, so |d| ≥ 1 for a rotation and the guard only moves rays within 1e-8 rad of
// parallel, where float32's own rounding of d_z (~1e-7·|d|₁ for a general rotation) is larger than d_z.
inline float ndc_direction_z(float z) {
  return fabs(z) < NDC_MIN_DIR_Z ? (z > 0.0f ? NDC_MIN_DIR_Z : -NDC_MIN_DIR_Z) : z;
}

// Change of the NDC origin between the ray of world direction `dir` and its neighbour of direction dir + step
// (both from world origin o). NDC origin: o_near = o + t·d on the plane z = −n, o_ndc = (2fx/(w·n)·o_near.x,
// 2fy/(h·n)·o_near.y, −1), o_near.x = o.x − (n + o.z)·d.x/d.z. The difference of d.x/d.z between the two rays is
// written (step.x·z0 − d.x·(z1 − z0))/(z0·z1) with z0 = d.z, z1 = d.z + step.z (so z1 − z0 = step.z), which does
// not cancel; each z goes through the guard above (then z1 − z0 is their difference), and hypot keeps the
// distance of such a far-off pair from overflowing in its squares.
inline float ndc_neighbour_distance(float3 o, float3 dir, float3 step, float sx, float sy) {
  const float n = NDC_NEAR_PLANE;
  const float z0 = ndc_direction_z(dir.z), z1 = ndc_direction_z(dir.z + step.z);
  const float dz = z0 == dir.z && z1 == dir.z + step.z ? step.z : z1 - z0;
  const float scale = -(n + o.z) / (z0 * z1);
  const float dx = scale * (step.x * z0 - dir.x * dz);
  const float dy = scale * (step.y * z0 - dir.y * dz);
  const float ex = sx / n * dx, ey = sy / n * dy;
  return hypot(ex, ey);
}

// Where the pair of neighbouring pixels that sets a pixel's NDC radius starts, relative to the pixel p (along an axis
// of `size` pixels): the pixel itself (p, p + 1), except in the last column / row, where google/mipnerf's
// LLFF._generate_rays pads its neighbour distances with the second-to-last pair's (dx[:, -2:-1]: pixels size − 3 and
// size − 2), two before p; a 2-pixel axis has only the pair (0, 1), and a 1-pixel axis looks one pixel outside.
inline float pair_start_shift(uint p, uint size) {
  if (p + 1 < size) return 0.0f;
  return size >= 3 ? -2.0f : -1.0f;
}

#if LENS_TABLES
// The normalised (u, v) of image position (pixel + offset) behind a lens, and the pixel's radius at unit depth, from
// the camera's table (entries [height][width], each u, v, radius, 0). Off the centre, first order in the offset along
// the differences to the next entry across and down (the previous one in the last column / row).
inline float3 lens_point(__global const float* cam, __global const float* table, uint px, uint py, uint width,
                         uint height, float offset_x, float offset_y) {
  const size_t pixel = (size_t)py * width + px;
  __global const float* here = table + 4 * pixel;
  float u = here[0], v = here[1];
  const float along_x = offset_x - 0.5f, along_y = offset_y - 0.5f;
  // An axis one pixel long has no next entry: a step of 1/f there, as the table's radius takes it.
  if (along_x != 0.0f && width == 1) u += along_x / cam[CAMERA_FOCAL_X];
  if (along_y != 0.0f && height == 1) v += along_y / cam[CAMERA_FOCAL_Y];
  if (along_x != 0.0f && width > 1) {
    // The difference to the next entry across (the previous one's to this in the last column).
    __global const float* a = px + 1 < width ? here : here - 4;
    u += along_x * (a[4] - a[0]);
    v += along_x * (a[5] - a[1]);
  }
  if (along_y != 0.0f && height > 1) {
    __global const float* b = py + 1 < height ? here : here - 4 * (size_t)width;
    u += along_y * (b[4 * (size_t)width] - b[0]);
    v += along_y * (b[4 * (size_t)width + 1] - b[1]);
  }
  return (float3)(u, v, here[2]);
}

// The world direction of image position (pixel + offset) behind the lens: camera_to_world·(u, −v, −1).
inline float3 lens_direction(__global const float* cam, __global const float* table, uint px, uint py, uint width,
                             uint height, float offset_x, float offset_y) {
  const float3 p = lens_point(cam, table, px, py, width, height, offset_x, offset_y);
  return camera_rotate(cam, (float3)(p.x, -p.y, -1.0f));
}

// A lens pixel's neighbour pairs for its NDC radius: along each axis of at least 2 pixels, the pair pair_start_shift
// picks (as for a pinhole) read from the table at the same sub-pixel offset — the first neighbour's direction and the
// step to the second. An axis one pixel long has no neighbour in the table and keeps the pinhole's pair (a step of
// 1/f back from the pixel), as the table's own radius takes 1/f for it.
inline void lens_ndc_pairs(__global const float* cam, __global const float* table, uint px, uint py, uint width,
                           uint height, float offset_x, float offset_y, float3* first_h, float3* step_h,
                           float3* first_v, float3* step_v) {
  if (width >= 2) {
    const uint start = (uint)((int)px + (int)pair_start_shift(px, width));
    *first_h = lens_direction(cam, table, start, py, width, height, offset_x, offset_y);
    *step_h = lens_direction(cam, table, start + 1, py, width, height, offset_x, offset_y) - *first_h;
  }
  if (height >= 2) {
    const uint start = (uint)((int)py + (int)pair_start_shift(py, height));
    *first_v = lens_direction(cam, table, px, start, width, height, offset_x, offset_y);
    *step_v = lens_direction(cam, table, px, start + 1, width, height, offset_x, offset_y) - *first_v;
  }
}
#endif

inline void write_nan_ray(size_t i, __global float* origins, __global float* directions, __global float* viewdirs,
                          __global float* radii, __global float* near, __global float* far,
                          __global float* lossmult) {
  const float3 nan3 = (float3)(NAN);
  store3(origins, i, nan3);
  store3(directions, i, nan3);
#if VIEW_DEPENDENCE
  store3(viewdirs, i, nan3);
#endif
  radii[i] = NAN;
  near[i] = NAN;
  far[i] = NAN;
  lossmult[i] = NAN;
}

// One item per ray. cameras [C][CAMERA_STRIDE], camera_ids, pixel_ids [R] → origins, directions, viewdirs [R][3],
// radii, near, far, lossmult [R]. Without VIEW_DEPENDENCE `viewdirs` is never written (any buffer may be passed).
__kernel void rays_fwd(__global const float* cameras, __global const uint* camera_ids,
                       __global const uint* pixel_ids, __global const float* lens_tables, __global float* origins, __global float* directions,
                       __global float* viewdirs, __global float* radii, __global float* near, __global float* far,
                       __global float* lossmult, const uint n_rays, const uint n_cameras, const ulong seed,
                       const uint step, const uint first_ray) {
  const size_t i = get_global_id(0);
  if (i >= n_rays) return;
  const uint camera_id = camera_ids[i];
  if (camera_id >= n_cameras) {
    write_nan_ray(i, origins, directions, viewdirs, radii, near, far, lossmult);
    return;
  }
  __global const float* cam = cameras + (size_t)camera_id * CAMERA_STRIDE;
  const uint width = (uint)cam[CAMERA_WIDTH], height = (uint)cam[CAMERA_HEIGHT];
  const uint pixel = pixel_ids[i];
  if (width == 0 || pixel / width >= height) {
    write_nan_ray(i, origins, directions, viewdirs, radii, near, far, lossmult);
    return;
  }
  const uint px = pixel % width, py = pixel / width;
#if SUBPIXEL_JITTER
  const float4 xi = rng_uniform4(seed, first_ray + (uint)i, step, 0, RNG_STREAM_SUBPIXEL);
  const float offset_x = xi.x, offset_y = xi.y;
#else
  const float offset_x = PIXEL_CENTER_OFFSET, offset_y = PIXEL_CENTER_OFFSET;
#endif
  // px − cx is exact for integer pixels and principal points on a half-pixel grid (< 2^22), so the one rounding
  // is in adding the sub-pixel offset, relative to the (small) distance from the principal point.
  const float fx = cam[CAMERA_FOCAL_X], fy = cam[CAMERA_FOCAL_Y];
  const float x_from_center = ((float)px - cam[CAMERA_CENTER_X]) + offset_x;
  const float y_from_center = ((float)py - cam[CAMERA_CENTER_Y]) + offset_y;
#if LENS_TABLES
  const uint lens_table = as_uint(cam[CAMERA_LENS_TABLE]);
  float3 dir_camera = (float3)(x_from_center / fx, -y_from_center / fy, -1.0f);
  float lens_radius = 0.0f;  // at unit depth, before the rotation's scale; 0: a pinhole camera
  if (lens_table != 0) {
    const float3 lens =
        lens_point(cam, lens_tables + 4 * (size_t)(lens_table - 1), px, py, width, height, offset_x, offset_y);
    dir_camera = (float3)(lens.x, -lens.y, -1.0f);
    lens_radius = lens.z;
  }
  const float3 dir = camera_rotate(cam, dir_camera);
#else
  const float3 dir = camera_rotate(cam, (float3)(x_from_center / fx, -y_from_center / fy, -1.0f));
#endif
  const float3 origin = camera_origin(cam);
#if VIEW_DEPENDENCE && UNIT_VIEWDIRS
  store3(viewdirs, i, dir / sqrt(dot(dir, dir)));
#elif VIEW_DEPENDENCE
  store3(viewdirs, i, dir);
#endif
#if RAY_SHAPE == RAY_SHAPE_CYLINDER
  const float n = NDC_NEAR_PLANE;
  const float w = cam[CAMERA_WIDTH], h = cam[CAMERA_HEIGHT];
  // Official convert_to_ndc, with d_z through the guard ndc_direction_z. The shifted origin's z is −n by
  // construction and is used exactly. The official direction a·(d/d_z − o_near/o_near_z) is computed as its exact
  // equal a·(o·d_z − o_z·d)/(n·d_z) (o_near = o + t·d, t = −(n + o_z)/d_z): the official form subtracts two terms
  // of size |d/d_z|, which for a large slope (a wide field of view, a ray nearly parallel to the near plane) leaves
  // an error u·|d/d_z| that can dwarf the result (a·o/n exactly when o_z = 0).
  const float dir_z = ndc_direction_z(dir.z);
  const float t_shift = -(n + origin.z) / dir_z;
  const float2 o_near = origin.xy + t_shift * dir.xy;
  // The NDC map: the run's (NDC_SCALE_X/Y, for a render camera of another field of view), else this camera's own
  // 2f/size (training: every camera shares it). −sx is −2f/w exactly as written before, bit for bit.
#ifdef NDC_SCALE_X
  const float sx = NDC_SCALE_X, sy = NDC_SCALE_Y;
#else
  const float sx = 2.0f * fx / w, sy = 2.0f * fy / h;
#endif
  const float ax = -sx, ay = -sy;
  store3(origins, i, (float3)(ax * o_near.x / -n, ay * o_near.y / -n, -1.0f));
  const float n_dir_z = n * dir_z;
  store3(directions, i,
         (float3)(ax * ((origin.x * dir_z - origin.z * dir.x) / n_dir_z),
                  ay * ((origin.y * dir_z - origin.z * dir.y) / n_dir_z), 2.0f));
  // The radius is the mean distance to the next pixel's NDC origin across and down, measured from the first pixel
  // of a pair of neighbours: this pixel and the next, or in the last column / row the pair the official code repeats
  // there (pair_start_shift).
  const float shift_x = pair_start_shift(px, width), shift_y = pair_start_shift(py, height);
  float3 step_h = camera_rotate(cam, (float3)(1.0f / fx, 0.0f, 0.0f));
  float3 step_v = camera_rotate(cam, (float3)(0.0f, -1.0f / fy, 0.0f));
  float3 first_h = dir + shift_x * step_h, first_v = dir + shift_y * step_v;
#if LENS_TABLES
  if (lens_table != 0) {
    lens_ndc_pairs(cam, lens_tables + 4 * (size_t)(lens_table - 1), px, py, width, height, offset_x, offset_y,
                   &first_h, &step_h, &first_v, &step_v);
  }
#endif
  const float dist_h = ndc_neighbour_distance(origin, first_h, step_h, sx, sy);
  const float dist_v = ndc_neighbour_distance(origin, first_v, step_v, sx, sy);
  radii[i] = 0.5f * (dist_h + dist_v) * RADIUS_PER_PIXEL_WIDTH;
#else
  store3(origins, i, origin);
  store3(directions, i, dir);
  __global const float* m = cam + CAMERA_TO_WORLD;
  const float column0 = sqrt(m[0] * m[0] + m[4] * m[4] + m[8] * m[8]);
#if LENS_TABLES
  radii[i] = lens_table != 0 ? column0 * lens_radius : column0 / fx * RADIUS_PER_PIXEL_WIDTH;
#else
  radii[i] = column0 / fx * RADIUS_PER_PIXEL_WIDTH;
#endif
#endif
  near[i] = cam[CAMERA_NEAR];
  far[i] = cam[CAMERA_FAR];
  lossmult[i] = cam[CAMERA_LOSSMULT];
}

#endif
