// Keyframe interpolation: Catmull–Rom positions, slerped orientations, linear intrinsics.
#include "data/paths/keyframes.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.hpp"
#include "core/vec3.hpp"
#include "data/pose.hpp"

namespace mipnerf::data {
namespace {

using Quaternion = std::array<double, 4>;  // (w, x, y, z)

double lerp(double a, double b, double t) { return a + (b - a) * t; }

// Uniform Catmull–Rom between p1 (t = 0) and p2 (t = 1), with neighbours p0 and p3.
Vec3 catmull_rom(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3, double t) {
  Vec3 out;
  const double t2 = t * t, t3 = t2 * t;
  for (int i = 0; i < 3; ++i) {
    out[i] = 0.5 * (2.0 * p1[i] + (p2[i] - p0[i]) * t + (2.0 * p0[i] - 5.0 * p1[i] + 4.0 * p2[i] - p3[i]) * t2 +
                    (3.0 * p1[i] - p0[i] - 3.0 * p2[i] + p3[i]) * t3);
  }
  return out;
}

Quaternion slerp(const Quaternion& a, Quaternion b, double t) {
  double cos_angle = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  if (cos_angle < 0.0) {  // q and −q are the same rotation: take the shorter arc
    for (double& v : b) v = -v;
    cos_angle = -cos_angle;
  }
  Quaternion out;
  if (cos_angle > 0.9995) {  // nearly equal: sin(angle) → 0, the normalised lerp is exact to rounding
    for (int i = 0; i < 4; ++i) out[i] = lerp(a[i], b[i], t);
  } else {
    const double angle = std::acos(cos_angle), s = std::sin(angle);
    const double wa = std::sin((1.0 - t) * angle) / s, wb = std::sin(t * angle) / s;
    for (int i = 0; i < 4; ++i) out[i] = wa * a[i] + wb * b[i];
  }
  const double n = std::sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2] + out[3] * out[3]);
  for (double& v : out) v /= n;
  return out;
}

void check_keyframes(const std::vector<Camera>& keyframes, uint32_t frames) {
  if (keyframes.empty()) throw Error("camera path: no keyframes to interpolate");
  if (frames == 0) throw Error("camera path: 0 frames asked for (give at least 1)");
  if (frames < keyframes.size()) {
    throw Error("camera path: " + std::to_string(frames) + " frames for " + std::to_string(keyframes.size()) +
                " keyframes would skip keyframes (give --frames of at least the number of keyframes)");
  }
  for (size_t k = 0; k < keyframes.size(); ++k) {
    const Camera& c = keyframes[k];
    if (c.width_px != keyframes[0].width_px || c.height_px != keyframes[0].height_px) {
      throw Error("camera path: keyframe " + std::to_string(k + 1) + " is " + std::to_string(c.width_px) + "x" +
                  std::to_string(c.height_px) + " but keyframe 1 is " + std::to_string(keyframes[0].width_px) + "x" +
                  std::to_string(keyframes[0].height_px) + " (keyframes to interpolate must share one image size)");
    }
    if (!c.lens.is_pinhole()) {
      throw Error("camera path: keyframe " + std::to_string(k + 1) + " has a lens; interpolation takes pinholes");
    }
  }
}

}  // namespace

std::array<double, 4> rotation_to_quaternion(const std::array<double, 12>& m) {
  // Shepperd's method: divide by the largest of 4w², 4x², 4y², 4z², never by a small number.
  const double r00 = m[0], r01 = m[1], r02 = m[2], r10 = m[4], r11 = m[5], r12 = m[6], r20 = m[8], r21 = m[9],
               r22 = m[10];
  const double trace = r00 + r11 + r22;
  Quaternion q;
  if (trace >= r00 && trace >= r11 && trace >= r22) {
    const double s = 2.0 * std::sqrt(std::max(0.0, 1.0 + trace));  // 4w
    q = {0.25 * s, (r21 - r12) / s, (r02 - r20) / s, (r10 - r01) / s};
  } else if (r00 >= r11 && r00 >= r22) {
    const double s = 2.0 * std::sqrt(std::max(0.0, 1.0 + r00 - r11 - r22));  // 4x
    q = {(r21 - r12) / s, 0.25 * s, (r01 + r10) / s, (r02 + r20) / s};
  } else if (r11 >= r22) {
    const double s = 2.0 * std::sqrt(std::max(0.0, 1.0 + r11 - r00 - r22));  // 4y
    q = {(r02 - r20) / s, (r01 + r10) / s, 0.25 * s, (r12 + r21) / s};
  } else {
    const double s = 2.0 * std::sqrt(std::max(0.0, 1.0 + r22 - r00 - r11));  // 4z
    q = {(r10 - r01) / s, (r02 + r20) / s, (r12 + r21) / s, 0.25 * s};
  }
  if (q[0] < 0.0) {
    for (double& v : q) v = -v;
  }
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (double& v : q) v /= n;
  return q;
}

std::array<double, 9> quaternion_to_rotation(const std::array<double, 4>& q) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  return {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
          2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
          2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
}

std::vector<Camera> interpolate_keyframes(const std::vector<Camera>& keyframes, uint32_t frames) {
  check_keyframes(keyframes, frames);
  const size_t count = keyframes.size();
  if (count == 1) return std::vector<Camera>(frames, keyframes.front());
  std::vector<Vec3> centres(count);
  std::vector<Quaternion> rotations(count);
  for (size_t k = 0; k < count; ++k) {
    centres[k] = camera_center(keyframes[k]);
    rotations[k] = rotation_to_quaternion(keyframes[k].camera_to_world);
  }
  // The end segments' outer neighbours, mirrored: p(−1) = 2 p(0) − p(1), p(K) = 2 p(K−1) − p(K−2).
  auto centre_at = [&](ptrdiff_t k) -> Vec3 {
    if (k < 0) return sub(scale(centres[0], 2.0), centres[1]);
    if (k >= static_cast<ptrdiff_t>(count)) return sub(scale(centres[count - 1], 2.0), centres[count - 2]);
    return centres[static_cast<size_t>(k)];
  };
  std::vector<Camera> out(frames);
  for (uint32_t i = 0; i < frames; ++i) {
    // The keyframe parameter s in [0, K − 1]; frame i of a path whose keyframes fall on frames can be exact.
    const double s = frames == 1 ? 0.0 : static_cast<double>(i) * static_cast<double>(count - 1) / (frames - 1);
    const size_t k = std::min(static_cast<size_t>(s), count - 2);
    const double t = s - static_cast<double>(k);
    const Camera& a = keyframes[k];
    const Camera& b = keyframes[k + 1];
    Camera c = a;
    const auto kk = static_cast<ptrdiff_t>(k);
    const Vec3 centre = catmull_rom(centre_at(kk - 1), centres[k], centres[k + 1], centre_at(kk + 2), t);
    const std::array<double, 9> r = quaternion_to_rotation(slerp(rotations[k], rotations[k + 1], t));
    c.camera_to_world = {r[0], r[1], r[2], centre[0], r[3], r[4], r[5], centre[1], r[6], r[7], r[8], centre[2]};
    if (t == 0.0) c.camera_to_world = a.camera_to_world;  // a keyframe's frame is the keyframe, bit for bit
    if (t == 1.0) c.camera_to_world = b.camera_to_world;
    c.focal_x_px = lerp(a.focal_x_px, b.focal_x_px, t);
    c.focal_y_px = lerp(a.focal_y_px, b.focal_y_px, t);
    c.center_x_px = lerp(a.center_x_px, b.center_x_px, t);
    c.center_y_px = lerp(a.center_y_px, b.center_y_px, t);
    c.near = lerp(a.near, b.near, t);
    c.far = lerp(a.far, b.far, t);
    c.lossmult = keyframes.front().lossmult;
    out[i] = c;
  }
  return out;
}

}  // namespace mipnerf::data
