// Writes COLMAP sparse models for tests, in the text and the binary format (colmap.github.io/format.html), from
// cameras given as our camera-to-world poses (OpenGL axes). Independent of the reader in host/data/colmap.cpp:
// the pose goes through a rotation matrix and Shepperd's quaternion extraction, the files are assembled by hand.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "data/pose.hpp"

namespace mipnerf::test {

struct ColmapTestCamera {
  uint32_t id;
  std::string model;  // "PINHOLE", "SIMPLE_PINHOLE", "SIMPLE_RADIAL", "OPENCV", ...
  int model_id;       // its id in cameras.bin (PINHOLE 1, SIMPLE_PINHOLE 0, SIMPLE_RADIAL 2, OPENCV 4)
  uint64_t width, height;
  std::vector<double> params;
};

struct ColmapTestImage {
  uint32_t id;
  uint32_t camera_id;
  std::string name;
  std::array<double, 9> world_to_camera{};  // R, row-major, OpenCV camera axes
  std::array<double, 3> t{};                // x_camera = R x_world + t
  std::array<double, 4> q{};                // (qw, qx, qy, qz) of R
};

struct ColmapTestPoint {
  uint64_t id;
  Vec3 xyz;
  std::vector<uint32_t> image_ids;
};

struct ColmapTestModel {
  std::vector<ColmapTestCamera> cameras;
  std::vector<ColmapTestImage> images;
  std::vector<ColmapTestPoint> points;
};

// Shepperd's method: the unit quaternion (w, x, y, z) of a rotation matrix, branching on the largest of
// the trace and the diagonal so the square root is of a number ≥ 1.
inline std::array<double, 4> quaternion_from_rotation(const std::array<double, 9>& r) {
  const double trace = r[0] + r[4] + r[8];
  std::array<double, 4> q{};
  if (trace >= r[0] && trace >= r[4] && trace >= r[8]) {
    const double s = 2.0 * std::sqrt(1.0 + trace);
    q = {0.25 * s, (r[7] - r[5]) / s, (r[2] - r[6]) / s, (r[3] - r[1]) / s};
  } else if (r[0] >= r[4] && r[0] >= r[8]) {
    const double s = 2.0 * std::sqrt(1.0 + r[0] - r[4] - r[8]);
    q = {(r[7] - r[5]) / s, 0.25 * s, (r[1] + r[3]) / s, (r[2] + r[6]) / s};
  } else if (r[4] >= r[8]) {
    const double s = 2.0 * std::sqrt(1.0 + r[4] - r[0] - r[8]);
    q = {(r[2] - r[6]) / s, (r[1] + r[3]) / s, 0.25 * s, (r[5] + r[7]) / s};
  } else {
    const double s = 2.0 * std::sqrt(1.0 + r[8] - r[0] - r[4]);
    q = {(r[3] - r[1]) / s, (r[2] + r[6]) / s, (r[5] + r[7]) / s, 0.25 * s};
  }
  return q;
}

// An image of camera `camera_id` whose pose is `camera_to_world` (OpenGL axes: x right, y up, looking down −z).
inline ColmapTestImage colmap_image(uint32_t id, uint32_t camera_id, const std::string& name,
                                    const data::Matrix34& camera_to_world) {
  ColmapTestImage image{id, camera_id, name, {}, {}, {}};
  // Camera-to-world in OpenCV axes flips the y and z columns; world-to-camera is its transpose.
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) {
      const double sign = col == 0 ? 1.0 : -1.0;
      image.world_to_camera[col * 3 + row] = sign * camera_to_world[row * 4 + col];
    }
  }
  for (int row = 0; row < 3; ++row) {
    image.t[row] = 0.0;
    for (int k = 0; k < 3; ++k) image.t[row] -= image.world_to_camera[row * 3 + k] * camera_to_world[k * 4 + 3];
  }
  image.q = quaternion_from_rotation(image.world_to_camera);
  return image;
}

// x_camera = R x + t (OpenCV axes): z is the depth.
inline Vec3 to_colmap_camera(const ColmapTestImage& image, const Vec3& x) {
  Vec3 c{};
  for (int row = 0; row < 3; ++row) {
    c[row] = image.t[row];
    for (int k = 0; k < 3; ++k) c[row] += image.world_to_camera[row * 3 + k] * x[k];
  }
  return c;
}

namespace colmap_detail {

inline std::string number(double v) {
  char text[40];
  std::snprintf(text, sizeof(text), "%.17g", v);
  return text;
}

template <typename T>
void put(std::string& out, T value) {
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));  // the test machines are little-endian, as COLMAP's files
  out.append(reinterpret_cast<const char*>(bytes), sizeof(T));
}

// Keypoint index of each (point, image) observation: the k-th point an image sees is its keypoint k.
inline std::map<std::pair<uint64_t, uint32_t>, uint32_t> keypoint_indices(const ColmapTestModel& model) {
  std::map<uint32_t, uint32_t> next;
  std::map<std::pair<uint64_t, uint32_t>, uint32_t> index;
  for (const auto& point : model.points) {
    for (uint32_t image_id : point.image_ids) index[{point.id, image_id}] = next[image_id]++;
  }
  return index;
}

// The keypoints of an image, in index order: (point id) per keypoint.
inline std::vector<uint64_t> keypoints_of(const ColmapTestModel& model, uint32_t image_id) {
  std::vector<uint64_t> ids;
  for (const auto& point : model.points) {
    for (uint32_t id : point.image_ids) {
      if (id == image_id) ids.push_back(point.id);
    }
  }
  return ids;
}

}  // namespace colmap_detail

inline std::string colmap_cameras_text(const ColmapTestModel& model) {
  using colmap_detail::number;
  std::string out = "# Camera list with one line of data per camera:\n#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n";
  out += "# Number of cameras: " + std::to_string(model.cameras.size()) + "\n";
  for (const auto& c : model.cameras) {
    out += std::to_string(c.id) + " " + c.model + " " + std::to_string(c.width) + " " + std::to_string(c.height);
    for (double p : c.params) out += " " + number(p);
    out += "\n";
  }
  return out;
}

inline std::string colmap_images_text(const ColmapTestModel& model) {
  using colmap_detail::number;
  std::string out =
      "# Image list with two lines of data per image:\n"
      "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n#   POINTS2D[] as (X, Y, POINT3D_ID)\n";
  out += "# Number of images: " + std::to_string(model.images.size()) + "\n";
  for (const auto& image : model.images) {
    out += std::to_string(image.id);
    for (double v : image.q) out += " " + number(v);
    for (double v : image.t) out += " " + number(v);
    out += " " + std::to_string(image.camera_id) + " " + image.name + "\n";
    std::string keypoints;
    for (uint64_t point_id : colmap_detail::keypoints_of(model, image.id)) {
      keypoints += (keypoints.empty() ? "" : " ") + std::string("1.5 2.5 ") + std::to_string(point_id);
    }
    out += keypoints + "\n";
  }
  return out;
}

inline std::string colmap_points_text(const ColmapTestModel& model) {
  using colmap_detail::number;
  const auto index = colmap_detail::keypoint_indices(model);
  std::string out =
      "# 3D point list with one line of data per point:\n"
      "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n";
  for (const auto& p : model.points) {
    out += std::to_string(p.id) + " " + number(p.xyz[0]) + " " + number(p.xyz[1]) + " " + number(p.xyz[2]) +
           " 200 100 50 0.5";
    for (uint32_t image_id : p.image_ids) {
      out += " " + std::to_string(image_id) + " " + std::to_string(index.at({p.id, image_id}));
    }
    out += "\n";
  }
  return out;
}

inline std::string colmap_cameras_binary(const ColmapTestModel& model) {
  using colmap_detail::put;
  std::string out;
  put<uint64_t>(out, model.cameras.size());
  for (const auto& c : model.cameras) {
    put<uint32_t>(out, c.id);
    put<int32_t>(out, c.model_id);
    put<uint64_t>(out, c.width);
    put<uint64_t>(out, c.height);
    for (double p : c.params) put<double>(out, p);
  }
  return out;
}

inline std::string colmap_images_binary(const ColmapTestModel& model) {
  using colmap_detail::put;
  std::string out;
  put<uint64_t>(out, model.images.size());
  for (const auto& image : model.images) {
    put<uint32_t>(out, image.id);
    for (double v : image.q) put<double>(out, v);
    for (double v : image.t) put<double>(out, v);
    put<uint32_t>(out, image.camera_id);
    out += image.name;
    out.push_back('\0');
    const auto keypoints = colmap_detail::keypoints_of(model, image.id);
    put<uint64_t>(out, keypoints.size());
    for (uint64_t point_id : keypoints) {
      put<double>(out, 1.5);
      put<double>(out, 2.5);
      put<uint64_t>(out, point_id);
    }
  }
  return out;
}

inline std::string colmap_points_binary(const ColmapTestModel& model) {
  using colmap_detail::put;
  const auto index = colmap_detail::keypoint_indices(model);
  std::string out;
  put<uint64_t>(out, model.points.size());
  for (const auto& p : model.points) {
    put<uint64_t>(out, p.id);
    for (double v : p.xyz) put<double>(out, v);
    out += "\xc8\x64\x32";  // colour 200 100 50
    put<double>(out, 0.5);
    put<uint64_t>(out, p.image_ids.size());
    for (uint32_t image_id : p.image_ids) {
      put<uint32_t>(out, image_id);
      put<uint32_t>(out, index.at({p.id, image_id}));
    }
  }
  return out;
}

inline void write_text_file(const std::string& path, const std::string& contents) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream(path, std::ios::binary) << contents;
}

// DIR/{cameras,images,points3D}.{txt,bin}.
inline void write_colmap_model(const std::string& dir, const ColmapTestModel& model, bool binary) {
  if (binary) {
    write_text_file(dir + "/cameras.bin", colmap_cameras_binary(model));
    write_text_file(dir + "/images.bin", colmap_images_binary(model));
    write_text_file(dir + "/points3D.bin", colmap_points_binary(model));
  } else {
    write_text_file(dir + "/cameras.txt", colmap_cameras_text(model));
    write_text_file(dir + "/images.txt", colmap_images_text(model));
    write_text_file(dir + "/points3D.txt", colmap_points_text(model));
  }
}

}  // namespace mipnerf::test
