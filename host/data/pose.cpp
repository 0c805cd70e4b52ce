// Pose reading, validation and geometry.
#include "data/pose.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/error.hpp"

namespace mipnerf::data {
namespace {

std::string three_digits(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3g", v);
  return text;
}

}  // namespace

Matrix34 from_columns(const Vec3& x, const Vec3& y, const Vec3& z, const Vec3& position) {
  return {x[0], y[0], z[0], position[0], x[1], y[1], z[1], position[1], x[2], y[2], z[2], position[2]};
}

Matrix34 view_matrix(const Vec3& z, const Vec3& up, const Vec3& position) {
  const Vec3 z_axis = normalize(z);
  const Vec3 x_axis = normalize(cross(up, z_axis));
  const Vec3 y_axis = normalize(cross(z_axis, x_axis));
  return from_columns(x_axis, y_axis, z_axis, position);
}

Matrix34 inverse_times(const Matrix34& a, const Matrix34& b) {
  Matrix34 out{};
  const Vec3 t = column(a, 3);
  for (int r = 0; r < 3; ++r) {
    const Vec3 row = column(a, r);  // row r of Rᵀ is column r of R
    for (int c = 0; c < 4; ++c) {
      const Vec3 bc = column(b, c);
      out[4 * r + c] = dot(row, c == 3 ? sub(bc, t) : bc);
    }
  }
  return out;
}

Matrix34 average_pose(const std::vector<Matrix34>& poses) {
  Vec3 center{0, 0, 0}, z{0, 0, 0}, up{0, 0, 0};
  for (const auto& p : poses) {
    center = add(center, column(p, 3));
    z = add(z, column(p, 2));
    up = add(up, column(p, 1));
  }
  return view_matrix(z, up, scale(center, 1.0 / static_cast<double>(poses.size())));
}

void recentre(std::vector<Matrix34>& poses) {
  const Matrix34 average = average_pose(poses);
  for (auto& pose : poses) pose = inverse_times(average, pose);
}

void scale_positions(std::vector<Matrix34>& poses, double s) {
  for (auto& pose : poses) {
    for (int r = 0; r < 3; ++r) pose[4 * r + 3] *= s;
  }
}

void centre_and_scale(std::vector<Matrix34>& poses, const Vec3& centre, double s) {
  for (auto& pose : poses) {
    for (int r = 0; r < 3; ++r) pose[4 * r + 3] = s * (pose[4 * r + 3] - centre[r]);
  }
}

double move_into_ndc_world(std::vector<Matrix34>& poses, double nearest_depth, const std::string& where) {
  if (poses.empty()) throw Error(where + ": no cameras to place in NDC");
  if (!(nearest_depth > 0.0) || !std::isfinite(nearest_depth)) {
    throw Error(where + ": NDC rays need the capture's nearest depth, a positive number; the file's near is " +
                std::to_string(nearest_depth) + " (set a positive \"near\" in it, or train with --set ray_shape=cone)");
  }
  const double s = 1.0 / (nearest_depth * 0.75);
  scale_positions(poses, s);
  recentre(poses);
  return s;
}

bool looks_forward(const std::vector<Matrix34>& poses) {
  Vec3 mean{0, 0, 0};
  for (const auto& p : poses) mean = add(mean, column(p, 2));
  if (dot(mean, mean) < 1e-12) return false;
  const Vec3 axis = normalize(mean);
  for (const auto& p : poses) {
    if (dot(column(p, 2), axis) < std::cos(M_PI / 4)) return false;  // more than 45° off the mean: > 90° spread
  }
  return true;
}

Matrix34 pose_from_json(const io::Json& value, const std::string& where) {
  const std::string shape_error = where + ": the pose must be a 4x4 (or 3x4) array of rows of numbers";
  if (!value.is_array() || (value.size() != 4 && value.size() != 3)) throw Error(shape_error);
  Matrix34 m{};
  for (size_t row = 0; row < value.size(); ++row) {
    const auto& r = value[row];
    if (!r.is_array() || r.size() != 4) throw Error(shape_error);
    // The whole row is checked for numbers first: the last row's message quotes all four of its entries.
    double values[4];
    for (size_t col = 0; col < 4; ++col) {
      if (!r[col].is_number()) throw Error(shape_error + " (row " + std::to_string(row) + " holds a " +
                                           io::json_type_name(r[col]) + ")");
      values[col] = r[col].get<double>();
      if (!std::isfinite(values[col])) {
        throw Error(where + ": the pose has a non-finite entry at row " + std::to_string(row) + ", column " +
                    std::to_string(col) + "; fix or drop this frame");
      }
    }
    for (size_t col = 0; col < 4; ++col) {
      if (row < 3) m[row * 4 + col] = values[col];
      else if (std::abs(values[col] - (col == 3 ? 1.0 : 0.0)) > 1e-6) {
        throw Error(where + ": the pose's last row must be 0 0 0 1 (a rigid camera-to-world matrix), got " +
                    three_digits(values[0]) + " " + three_digits(values[1]) + " " + three_digits(values[2]) + " " +
                    three_digits(values[3]));
      }
    }
  }
  check_rigid_pose(m, where);
  return m;
}

io::Json pose_to_json(const Matrix34& m) {
  io::Json rows = io::Json::array();
  for (int row = 0; row < 3; ++row) rows.push_back({m[row * 4], m[row * 4 + 1], m[row * 4 + 2], m[row * 4 + 3]});
  rows.push_back({0.0, 0.0, 0.0, 1.0});
  return rows;
}

void check_rigid_pose(const Matrix34& m, const std::string& where) {
  for (double v : m) {
    if (!std::isfinite(v)) throw Error(where + ": the pose has a non-finite entry; fix or drop this frame");
  }
  auto r = [&m](int row, int col) { return m[row * 4 + col]; };
  double deviation = 0.0;  // max |RᵀR − I|
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double dot = r(0, i) * r(0, j) + r(1, i) * r(1, j) + r(2, i) * r(2, j);
      deviation = std::max(deviation, std::abs(dot - (i == j ? 1.0 : 0.0)));
    }
  }
  const double det = r(0, 0) * (r(1, 1) * r(2, 2) - r(1, 2) * r(2, 1)) -
                     r(0, 1) * (r(1, 0) * r(2, 2) - r(1, 2) * r(2, 0)) +
                     r(0, 2) * (r(1, 0) * r(2, 1) - r(1, 1) * r(2, 0));
  if (deviation > kRigidTolerance) {
    throw Error(where + ": the pose's rotation is not orthonormal (max |R^T R - I| = " + three_digits(deviation) +
                ", tolerance " + three_digits(kRigidTolerance) +
                "): the matrix is scaled or sheared; scale the scene through the translations only");
  }
  if (std::abs(det - 1.0) > kRigidTolerance) {
    throw Error(where + ": the pose's rotation has determinant " + three_digits(det) +
                " instead of +1: it is a reflection (a left-handed or mirrored axis convention); "
                "convert it to OpenGL/Blender axes (x right, y up, camera looking down -z)");
  }
}

Matrix34 look_at_pose(const Vec3& eye, const Vec3& target, const Vec3& up) {
  const Vec3 forward = normalize({target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]});
  const Vec3 right = normalize(cross(forward, up));
  const Vec3 up_camera = cross(right, forward);
  // Columns: x_camera = right, y_camera = up, z_camera = −forward (the camera looks down −z).
  return {right[0], up_camera[0], -forward[0], eye[0],  //
          right[1], up_camera[1], -forward[1], eye[1],  //
          right[2], up_camera[2], -forward[2], eye[2]};
}

Vec3 camera_center(const Camera& camera) {
  const auto& m = camera.camera_to_world;
  return {m[3], m[7], m[11]};
}

Vec3 optical_axis(const Camera& camera) {
  const auto& m = camera.camera_to_world;
  return normalize({-m[2], -m[6], -m[10]});
}

std::optional<Vec3> closest_point_to_axes(const std::vector<Camera>& cameras) {
  double a[3][3] = {};
  double b[3] = {};
  for (const auto& camera : cameras) {
    const Vec3 d = optical_axis(camera);
    const Vec3 o = camera_center(camera);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        const double p = (i == j ? 1.0 : 0.0) - d[i] * d[j];
        a[i][j] += p;
        b[i] += p * o[j];
      }
    }
  }
  // Cramer's rule; the system is singular when all axes are parallel (or there are none).
  const double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                     a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                     a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  const double scale = cameras.size() * cameras.size() * cameras.size();
  if (cameras.empty() || std::abs(det) < 1e-9 * scale) return std::nullopt;
  Vec3 p{};
  for (int k = 0; k < 3; ++k) {
    double m[3][3];
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) m[i][j] = j == k ? b[i] : a[i][j];
    }
    p[k] = (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
            m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])) /
           det;
  }
  return p;
}

WorldAroundCameras world_around_cameras(const std::vector<Matrix34>& poses, const std::string& where) {
  if (poses.empty()) throw Error(where + ": no cameras to centre the world on");
  std::vector<Camera> cameras(poses.size());
  for (size_t i = 0; i < poses.size(); ++i) cameras[i].camera_to_world = poses[i];
  WorldAroundCameras world;
  if (const auto look_at = closest_point_to_axes(cameras)) {
    world.centre = *look_at;
  } else {
    world.centre_is_look_at = false;
    Vec3 sum{0, 0, 0};
    for (const auto& pose : poses) sum = add(sum, column(pose, 3));
    world.centre = {sum[0] / poses.size(), sum[1] / poses.size(), sum[2] / poses.size()};
  }
  double mean_square = 0.0;
  for (const auto& pose : poses) {
    const Vec3 offset = sub(column(pose, 3), world.centre);
    mean_square += dot(offset, offset) / static_cast<double>(poses.size());
  }
  if (!(mean_square > 0.0) || !std::isfinite(mean_square)) {
    throw Error(where + ": every camera sits at the scene's centre: a capture's cameras need distinct positions");
  }
  world.scale = 1.0 / std::sqrt(mean_square);
  return world;
}

}  // namespace mipnerf::data
