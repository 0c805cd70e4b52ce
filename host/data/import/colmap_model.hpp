// Readers of COLMAP sparse models (colmap.github.io/format.html): cameras, images and points3D, in the text
// format (.txt) and the binary format (.bin, little-endian). Each file's parser takes the file's contents in
// memory and a name for messages, so a fuzzer can call it directly; every malformed input is a one-line
// mipnerf::Error naming the file (and the line, for text) and what is wrong. The parsers read what the files say;
// what mipnerf-cl can use of it (pinhole cameras only) is decided by the importer (data/import/colmap_import.hpp).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace mipnerf::data {

// A COLMAP camera model: its id in cameras.bin, its name in cameras.txt, and how many parameters follow.
struct ColmapCameraModel {
  int id;
  const char* name;
  int num_params;
};
// Every model COLMAP defines (ids 0 … 17), to read any model file; the ones mipnerf-cl reads a camera of are the
// rows of core/lens_models.hpp. nullptr for an unknown id or name.
const ColmapCameraModel* find_colmap_camera_model(int id);
const ColmapCameraModel* find_colmap_camera_model(std::string_view name);

struct ColmapCamera {
  uint32_t id = 0;
  const ColmapCameraModel* model = nullptr;
  uint64_t width = 0, height = 0;  // pixels, > 0
  std::vector<double> params;      // model->num_params values, finite; COLMAP's order (PINHOLE: fx, fy, cx, cy)
  uint64_t line = 0;               // text: the line it was read from (for messages); binary: 0
};

struct ColmapImage {
  uint32_t id = 0;
  // World-to-camera: x_camera = R(q) x_world + t, OpenCV camera axes (x right, y down, z forward). q is
  // (qw, qx, qy, qz), Hamilton convention, normalised here (the file's norm is within kQuaternionTolerance of 1).
  std::array<double, 4> qvec{1, 0, 0, 0};
  std::array<double, 3> tvec{0, 0, 0};
  uint32_t camera_id = 0;
  std::string name;           // the image file, relative to COLMAP's image folder
  uint64_t num_points2d = 0;  // keypoints listed for it (their coordinates are not kept)
  uint64_t line = 0;          // text: its first line; binary: 0
};

struct ColmapPoint {
  uint64_t id = 0;
  std::array<double, 3> xyz{0, 0, 0};  // world, finite
  std::vector<uint32_t> image_ids;     // the images that observe it (its track; keypoint indices dropped)
  uint64_t line = 0;                   // text: its line; binary: 0
};

// How far a file's quaternion norm may be from 1: COLMAP writes unit quaternions with 17 significant digits
// (older versions with 6, so ~1e-6 off); anything further is not a rotation COLMAP wrote.
constexpr double kQuaternionTolerance = 1e-3;

// The parsers. `where` names the file in messages (its path). Text files: '#' comment lines and blank lines are
// skipped (images.txt: two lines per image, the second, the keypoints, possibly empty); fields are separated by
// spaces. Binary files: counts are checked against the bytes left before anything is allocated, and bytes after
// the last record are an error.
std::vector<ColmapCamera> parse_colmap_cameras_text(std::string_view text, const std::string& where);
std::vector<ColmapCamera> parse_colmap_cameras_binary(std::string_view bytes, const std::string& where);
std::vector<ColmapImage> parse_colmap_images_text(std::string_view text, const std::string& where);
std::vector<ColmapImage> parse_colmap_images_binary(std::string_view bytes, const std::string& where);
std::vector<ColmapPoint> parse_colmap_points_text(std::string_view text, const std::string& where);
std::vector<ColmapPoint> parse_colmap_points_binary(std::string_view bytes, const std::string& where);

struct ColmapModel {
  std::string dir;
  bool binary = true;  // read from the .bin files (COLMAP's default), else the .txt files
  std::vector<ColmapCamera> cameras;
  std::vector<ColmapImage> images;
  std::vector<ColmapPoint> points;
  std::string file(const char* stem) const;  // "DIR/cameras.bin" or "DIR/cameras.txt"
  // Where a record came from, for messages: "DIR/images.txt:7: image 3" (text) or "DIR/images.bin: image 3".
  std::string where(const char* stem, uint64_t line, const char* kind, uint64_t id) const;
};

// Checks what spans files: ids unique per kind, every image's camera exists, every track's image exists, at least
// one image. Throws naming the record (file and line or record) that is wrong.
void check_colmap_model(const ColmapModel& model);

// Reads SPARSE_DIR/{cameras,images,points3D}.bin, else the .txt files (COLMAP prefers binary when both are there),
// and checks the model. Throws naming what is missing when the folder holds neither set (whole).
ColmapModel read_colmap_model(const std::string& sparse_dir);

}  // namespace mipnerf::data
