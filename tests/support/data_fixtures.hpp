// Helpers of the tests/data suite: temporary folders and small datasets written on the fly.
#pragma once

#include <atomic>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

#include "core/error.hpp"
#include "data/dataset.hpp"
#include "data/pose.hpp"
#include "io/file.hpp"
#include "io/json.hpp"
#include "io/png.hpp"

namespace mipnerf::test {

// A fresh folder under the system temp folder, removed (with its contents) on destruction.
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    path_ = (std::filesystem::temp_directory_path() /
             ("mipnerf-data-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++)))
                .string();
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }
  std::string operator/(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

// Sample value of pixel (x, y), channel c, image k of a synthetic RGBA image: distinct 8-bit codes.
inline uint8_t test_code(int k, uint32_t x, uint32_t y, int c) {
  return static_cast<uint8_t>((37 * k + 11 * x + 7 * y + 61 * c + (x * y) % 13) % 256);
}

inline std::vector<uint8_t> test_rgba8(int k, uint32_t width, uint32_t height) {
  std::vector<uint8_t> rgba(static_cast<size_t>(width) * height * 4);
  for (uint32_t y = 0; y < height; ++y)
    for (uint32_t x = 0; x < width; ++x)
      for (int c = 0; c < 4; ++c) rgba[(static_cast<size_t>(y) * width + x) * 4 + c] = test_code(k, x, y, c);
  return rgba;
}

// A camera on a circle of radius 4 at height z, looking at the origin.
inline data::Matrix34 test_pose(int k) {
  const double angle = 0.7 * k + 0.3;
  return data::look_at_pose({4.0 * std::cos(angle), 4.0 * std::sin(angle), 1.0 + 0.2 * k}, {0, 0, 0}, {0, 0, 1});
}

// Writes DIR/transforms_<split>.json (camera_angle_x) and DIR/<split>/r_k.png (test_rgba8) for `count` frames.
inline void write_blender_split(const std::string& dir, const std::string& split, int count, uint32_t width,
                                uint32_t height, double camera_angle_x = 0.6911112070083618) {
  io::Json frames = io::Json::array();
  for (int k = 0; k < count; ++k) {
    const auto rgba = test_rgba8(k, width, height);
    io::write_png8(dir + "/" + split + "/r_" + std::to_string(k) + ".png", width, height, 4, rgba.data());
    frames.push_back({{"file_path", "./" + split + "/r_" + std::to_string(k)},
                      {"rotation", 0.0125},
                      {"transform_matrix", data::pose_to_json(test_pose(k))}});
  }
  io::write_json(dir + "/transforms_" + split + ".json", {{"camera_angle_x", camera_angle_x}, {"frames", frames}});
}

// The message of the mipnerf::Error `body` throws ("" when it throws none; other exceptions propagate).
template <typename Body>
std::string error_of(Body body) {
  try {
    body();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

inline bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// Every camera of a capture that holds out every 8th view (transforms.json, LLFF), in file order: its train and
// test splits interleaved back.
inline std::vector<Camera> every_camera_in_file_order(const data::Dataset& dataset) {
  const auto& train = dataset.split("train").cameras;
  const auto& test = dataset.split("test").cameras;
  std::vector<Camera> cameras;
  size_t next_train = 0, next_test = 0;
  for (size_t i = 0; i < train.size() + test.size(); ++i) {
    cameras.push_back(i % 8 == 0 ? test[next_test++] : train[next_train++]);
  }
  return cameras;
}

}  // namespace mipnerf::test
