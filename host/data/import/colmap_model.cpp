// COLMAP sparse models: the text and binary parsers of cameras, images and points3D, and the model's cross-file
// checks. Every failure is a one-line mipnerf::Error naming the file (and line); no other exception leaves here.
#include "data/import/colmap_model.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <type_traits>
#include <unordered_map>
#include <unordered_set>

#include "core/error.hpp"
#include "io/file.hpp"

namespace mipnerf::data {
namespace fs = std::filesystem;

namespace {

// The models COLMAP defines (src/colmap/sensor/models.h): id, name, parameter count, to read a model file whatever
// its cameras; which of them a camera is read of, and how, is core/lens_models.hpp's.
constexpr ColmapCameraModel kModels[] = {
    {0, "SIMPLE_PINHOLE", 3},
    {1, "PINHOLE", 4},
    {2, "SIMPLE_RADIAL", 4},
    {3, "RADIAL", 5},
    {4, "OPENCV", 8},
    {5, "OPENCV_FISHEYE", 8},
    {6, "FULL_OPENCV", 12},
    {7, "FOV", 5},
    {8, "SIMPLE_RADIAL_FISHEYE", 4},
    {9, "RADIAL_FISHEYE", 5},
    {10, "THIN_PRISM_FISHEYE", 12},
    {11, "RAD_TAN_THIN_PRISM_FISHEYE", 16},
    {12, "SIMPLE_DIVISION", 4},
    {13, "DIVISION", 5},
    {14, "SIMPLE_FISHEYE", 3},
    {15, "FISHEYE", 4},
    {16, "EUCM", 6},
    {17, "EQUIRECTANGULAR", 2},
};
constexpr int kFewestParams = 2;

// Larger sides are not a camera image (and would overflow the loader's 32-bit sizes).
constexpr uint64_t kMaxImageSide = 1u << 20;

std::string six_digits(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.6g", v);
  return text;
}

// ---- validation shared by both formats ----

// Checks a name is usable as a file name in JSON: non-empty, no control characters, well-formed UTF-8 (no overlong
// forms or surrogates: the JSON writer refuses those).
void check_name(std::string_view name, const std::string& at) {
  if (name.empty()) throw Error(at + ": the image has an empty name");
  auto byte = [&name](size_t i) { return i < name.size() ? static_cast<unsigned char>(name[i]) : 0u; };
  for (size_t i = 0; i < name.size();) {
    const unsigned c = byte(i);
    if (c < 0x20 || c == 0x7F) throw Error(at + ": the image name holds a control character");
    // Continuation bytes are 0x80..0xBF; the first one after some leads has a narrower range.
    unsigned low = 0x80, high = 0xBF;
    size_t extra = 0;
    if (c < 0x80) {
      extra = 0;
    } else if (c >= 0xC2 && c <= 0xDF) {
      extra = 1;
    } else if (c >= 0xE0 && c <= 0xEF) {
      extra = 2;
      if (c == 0xE0) low = 0xA0;
      if (c == 0xED) high = 0x9F;
    } else if (c >= 0xF0 && c <= 0xF4) {
      extra = 3;
      if (c == 0xF0) low = 0x90;
      if (c == 0xF4) high = 0x8F;
    } else {
      throw Error(at + ": the image name is not valid UTF-8");
    }
    for (size_t k = 1; k <= extra; ++k) {
      const unsigned next = byte(i + k);
      if (next < (k == 1 ? low : 0x80) || next > (k == 1 ? high : 0xBF)) {
        throw Error(at + ": the image name is not valid UTF-8");
      }
    }
    i += 1 + extra;
  }
}

// Normalises q, or throws when it is zero or not unit length within kQuaternionTolerance.
std::array<double, 4> checked_quaternion(const std::array<double, 4>& q, const std::string& at) {
  for (double v : q) {
    if (!std::isfinite(v)) throw Error(at + ": the quaternion has a non-finite value");
  }
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (norm == 0.0) throw Error(at + ": the quaternion (QW QX QY QZ) is zero: not a rotation");
  if (std::abs(norm - 1.0) > kQuaternionTolerance) {
    throw Error(at + ": the quaternion (QW QX QY QZ) has norm " + six_digits(norm) +
                ", not 1: not a rotation COLMAP wrote");
  }
  return {q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm};
}

void check_size(uint64_t width, uint64_t height, const std::string& at) {
  if (width == 0 || height == 0 || width > kMaxImageSide || height > kMaxImageSide) {
    throw Error(at + ": image size " + std::to_string(width) + "x" + std::to_string(height) +
                " is not a camera's (each side must be 1 to " + std::to_string(kMaxImageSide) + " pixels)");
  }
}

// ---- text ----

struct Line {
  uint64_t number;
  std::string_view text;
};

std::vector<Line> split_lines(std::string_view text) {
  std::vector<Line> lines;
  uint64_t number = 0;
  size_t start = 0;
  while (start <= text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    lines.push_back({++number, line});
    if (end == text.size()) break;
    start = end + 1;
  }
  return lines;
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\v' || c == '\f' || c == '\r'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

bool skipped(std::string_view line) {
  line = trim(line);
  return line.empty() || line.front() == '#';
}

std::vector<std::string_view> fields(std::string_view line) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_space(line[i])) ++i;
    const size_t start = i;
    while (i < line.size() && !is_space(line[i])) ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

// A quoted, shortened copy of a token for messages.
std::string quoted(std::string_view token) {
  std::string shown(token.substr(0, 24));
  for (char& c : shown) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7F) c = '?';
  }
  return "'" + shown + (token.size() > 24 ? "...'" : "'");
}

template <typename T>
T parse_integer(std::string_view token, const char* what, const std::string& at) {
  T value{};
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec == std::errc::result_out_of_range) throw Error(at + ": " + what + " " + quoted(token) + " is out of range");
  if (ec != std::errc() || end != token.data() + token.size()) {
    throw Error(at + ": " + what +
                (std::is_unsigned_v<T> ? " must be a non-negative integer, got " : " must be an integer, got ") +
                quoted(token));
  }
  return value;
}

double parse_number(std::string_view token, const char* what, const std::string& at) {
  double value = 0.0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec != std::errc() || end != token.data() + token.size()) {
    throw Error(at + ": " + what + " must be a number, got " + quoted(token));
  }
  if (!std::isfinite(value)) throw Error(at + ": " + what + " is not finite (" + quoted(token) + ")");
  return value;
}

std::string line_at(const std::string& where, uint64_t line) { return where + ":" + std::to_string(line); }

// ---- binary ----

// Reads little-endian values from the bytes in memory. Every read checks the bytes left, and every count read
// from the file is checked against them before anything is allocated: a damaged count is an error, not a
// huge allocation.
class ByteReader {
 public:
  ByteReader(std::string_view bytes, const std::string& where, const char* kind)
      : bytes_(bytes), where_(where), kind_(kind) {}

  // The record being read, for messages ("camera 3 of 10").
  void set_record(uint64_t index, uint64_t count) {
    index_ = index;
    count_ = count;
  }
  size_t left() const { return bytes_.size() - pos_; }

  uint64_t u64(const char* what) { return unsigned_value(8, what); }
  uint32_t u32(const char* what) { return static_cast<uint32_t>(unsigned_value(4, what)); }
  int32_t i32(const char* what) {
    const uint32_t u = u32(what);
    int32_t v;
    std::memcpy(&v, &u, 4);
    return v;
  }
  uint8_t u8(const char* what) { return static_cast<uint8_t>(unsigned_value(1, what)); }
  double f64(const char* what) {
    const uint64_t u = u64(what);
    double v;
    std::memcpy(&v, &u, 8);
    if (!std::isfinite(v)) throw Error(record() + ": " + what + " is not finite");
    return v;
  }
  // A NUL-terminated string.
  std::string_view c_string(const char* what) {
    const size_t end = bytes_.find('\0', pos_);
    if (end == std::string_view::npos) truncated(what, left() + 1);
    std::string_view s = bytes_.substr(pos_, end - pos_);
    pos_ = end + 1;
    return s;
  }
  void skip(uint64_t count, const char* what) {
    if (count > left()) truncated(what, count);
    pos_ += count;
  }
  // Throws unless `count` records of at least `min_bytes` each fit in the bytes left.
  void check_count(uint64_t count, uint64_t min_bytes, const char* what) {
    if (count > left() / min_bytes) {
      throw Error(record() + ": " + what + " is " + std::to_string(count) + " but only " + std::to_string(left()) +
                  " bytes follow (each takes at least " + std::to_string(min_bytes) +
                  "): the file is truncated or damaged");
    }
  }
  void check_end() {
    if (left() != 0) {
      throw Error(where_ + ": " + std::to_string(left()) + " bytes follow the last " + kind_ +
                  ": the file is damaged or not a COLMAP " + kind_ + "s file");
    }
  }
  std::string record() const {
    if (count_ == 0) return where_;
    return where_ + ": " + kind_ + " record " + std::to_string(index_ + 1) + " of " + std::to_string(count_);
  }

 private:
  uint64_t unsigned_value(int size, const char* what) {
    if (left() < static_cast<size_t>(size)) truncated(what, size);
    uint64_t v = 0;
    for (int k = size - 1; k >= 0; --k) v = (v << 8) | static_cast<unsigned char>(bytes_[pos_ + k]);
    pos_ += size;
    return v;
  }
  [[noreturn]] void truncated(const char* what, uint64_t needed) const {
    throw Error(record() + ": truncated: " + what + " needs " + std::to_string(needed) + " bytes, " +
                std::to_string(left()) + " are left at byte " + std::to_string(pos_));
  }

  std::string_view bytes_;
  size_t pos_ = 0;
  const std::string& where_;
  const char* kind_;
  uint64_t index_ = 0, count_ = 0;
};

std::string id_at(const std::string& at, const char* kind, uint64_t id) {
  return at + ": " + kind + " " + std::to_string(id);
}

// "camera 3: its RADIAL parameter 5 of 5", for the messages about one of a camera's parameters.
std::string parameter_name(const ColmapCamera& camera, size_t index) {
  return "camera " + std::to_string(camera.id) + ": its " + camera.model->name + " parameter " +
         std::to_string(index + 1) + " of " + std::to_string(camera.model->num_params);
}

}  // namespace

const ColmapCameraModel* find_colmap_camera_model(int id) {
  for (const auto& model : kModels) {
    if (model.id == id) return &model;
  }
  return nullptr;
}

const ColmapCameraModel* find_colmap_camera_model(std::string_view name) {
  for (const auto& model : kModels) {
    if (name == model.name) return &model;
  }
  return nullptr;
}

// ---- cameras ----

std::vector<ColmapCamera> parse_colmap_cameras_text(std::string_view text, const std::string& where) {
  std::vector<ColmapCamera> cameras;
  for (const Line& line : split_lines(text)) {
    if (skipped(line.text)) continue;
    const std::string at = line_at(where, line.number);
    const auto f = fields(line.text);
    if (f.size() < 4) {
      throw Error(at + ": expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS..., got " + std::to_string(f.size()) +
                  " fields");
    }
    ColmapCamera camera;
    camera.line = line.number;
    camera.id = parse_integer<uint32_t>(f[0], "CAMERA_ID", at);
    camera.model = find_colmap_camera_model(f[1]);
    if (!camera.model) throw Error(id_at(at, "camera", camera.id) + ": unknown camera model " + quoted(f[1]));
    camera.width = parse_integer<uint64_t>(f[2], "WIDTH", at);
    camera.height = parse_integer<uint64_t>(f[3], "HEIGHT", at);
    check_size(camera.width, camera.height, id_at(at, "camera", camera.id));
    if (f.size() - 4 != static_cast<size_t>(camera.model->num_params)) {
      throw Error(id_at(at, "camera", camera.id) + ": " + camera.model->name + " takes " +
                  std::to_string(camera.model->num_params) + " parameters, the line has " +
                  std::to_string(f.size() - 4));
    }
    for (size_t k = 4; k < f.size(); ++k) {
      camera.params.push_back(parse_number(f[k], parameter_name(camera, k - 4).c_str(), at));
    }
    cameras.push_back(std::move(camera));
  }
  return cameras;
}

std::vector<ColmapCamera> parse_colmap_cameras_binary(std::string_view bytes, const std::string& where) {
  ByteReader in(bytes, where, "camera");
  const uint64_t count = in.u64("the number of cameras");
  in.check_count(count, 24 + 8 * kFewestParams, "the number of cameras");
  std::vector<ColmapCamera> cameras;
  cameras.reserve(count);
  for (uint64_t i = 0; i < count; ++i) {
    in.set_record(i, count);
    ColmapCamera camera;
    camera.id = in.u32("CAMERA_ID");
    const int32_t model_id = in.i32("MODEL_ID");
    const std::string at = id_at(in.record(), "camera", camera.id);
    camera.model = find_colmap_camera_model(model_id);
    if (!camera.model) throw Error(at + ": unknown camera model id " + std::to_string(model_id));
    camera.width = in.u64("WIDTH");
    camera.height = in.u64("HEIGHT");
    check_size(camera.width, camera.height, at);
    for (int k = 0; k < camera.model->num_params; ++k) {
      camera.params.push_back(in.f64(parameter_name(camera, static_cast<size_t>(k)).c_str()));
    }
    cameras.push_back(std::move(camera));
  }
  in.check_end();
  return cameras;
}

// ---- images ----

std::vector<ColmapImage> parse_colmap_images_text(std::string_view text, const std::string& where) {
  const auto lines = split_lines(text);
  std::vector<ColmapImage> images;
  for (size_t i = 0; i < lines.size(); ++i) {
    if (skipped(lines[i].text)) continue;
    const std::string at = line_at(where, lines[i].number);
    const auto f = fields(lines[i].text);
    if (f.size() < 10) {
      throw Error(at + ": expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME, got " + std::to_string(f.size()) +
                  " fields");
    }
    ColmapImage image;
    image.line = lines[i].number;
    image.id = parse_integer<uint32_t>(f[0], "IMAGE_ID", at);
    const std::string image_at = id_at(at, "image", image.id);
    std::array<double, 4> q{};
    static const char* const kQ[] = {"QW", "QX", "QY", "QZ"};
    for (int k = 0; k < 4; ++k) q[k] = parse_number(f[1 + k], kQ[k], image_at);
    static const char* const kT[] = {"TX", "TY", "TZ"};
    for (int k = 0; k < 3; ++k) image.tvec[k] = parse_number(f[5 + k], kT[k], image_at);
    image.qvec = checked_quaternion(q, image_at);
    image.camera_id = parse_integer<uint32_t>(f[8], "CAMERA_ID", image_at);
    // NAME is the rest of the line, so names with spaces survive.
    image.name = std::string(trim(lines[i].text.substr(f[9].data() - lines[i].text.data())));
    check_name(image.name, image_at);
    // The second line lists the keypoints as X Y POINT3D_ID triples; it may be empty, or absent at the end.
    if (i + 1 < lines.size() && !skipped(lines[i + 1].text)) {
      ++i;
      const std::string points_at = line_at(where, lines[i].number);
      const auto p = fields(lines[i].text);
      if (p.size() % 3 != 0) {
        throw Error(points_at + ": the keypoints of image " + std::to_string(image.id) +
                    " must be X Y POINT3D_ID triples, the line has " + std::to_string(p.size()) + " fields");
      }
      for (size_t k = 0; k < p.size(); k += 3) {
        parse_number(p[k], "a keypoint's X", points_at);
        parse_number(p[k + 1], "a keypoint's Y", points_at);
        if (parse_integer<int64_t>(p[k + 2], "POINT3D_ID", points_at) < -1) {
          throw Error(points_at + ": POINT3D_ID must be -1 (none) or an id, got " + quoted(p[k + 2]));
        }
      }
      image.num_points2d = p.size() / 3;
    } else if (i + 1 < lines.size() && trim(lines[i + 1].text).empty()) {
      ++i;  // an image without keypoints: its empty second line
    }
    images.push_back(std::move(image));
  }
  return images;
}

std::vector<ColmapImage> parse_colmap_images_binary(std::string_view bytes, const std::string& where) {
  ByteReader in(bytes, where, "image");
  const uint64_t count = in.u64("the number of images");
  // id, 7 doubles, camera id, at least a 1-character name and its NUL, the keypoint count.
  in.check_count(count, 4 + 7 * 8 + 4 + 2 + 8, "the number of images");
  std::vector<ColmapImage> images;
  images.reserve(count);
  for (uint64_t i = 0; i < count; ++i) {
    in.set_record(i, count);
    ColmapImage image;
    image.id = in.u32("IMAGE_ID");
    const std::string at = id_at(in.record(), "image", image.id);
    std::array<double, 4> q{};
    for (double& v : q) v = in.f64("the quaternion");
    for (double& v : image.tvec) v = in.f64("the translation");
    image.qvec = checked_quaternion(q, at);
    image.camera_id = in.u32("CAMERA_ID");
    image.name = std::string(in.c_string("the name (NUL-terminated)"));
    check_name(image.name, at);
    image.num_points2d = in.u64("the number of keypoints");
    in.check_count(image.num_points2d, 24, "the number of keypoints");
    for (uint64_t k = 0; k < image.num_points2d; ++k) {
      in.f64("a keypoint's X");
      in.f64("a keypoint's Y");
      in.u64("a keypoint's POINT3D_ID");
    }
    images.push_back(std::move(image));
  }
  in.check_end();
  return images;
}

// ---- points ----

std::vector<ColmapPoint> parse_colmap_points_text(std::string_view text, const std::string& where) {
  std::vector<ColmapPoint> points;
  for (const Line& line : split_lines(text)) {
    if (skipped(line.text)) continue;
    const std::string at = line_at(where, line.number);
    const auto f = fields(line.text);
    if (f.size() < 8 || (f.size() - 8) % 2 != 0) {
      throw Error(at + ": expected POINT3D_ID X Y Z R G B ERROR and IMAGE_ID POINT2D_IDX pairs, got " +
                  std::to_string(f.size()) + " fields");
    }
    ColmapPoint point;
    point.line = line.number;
    point.id = parse_integer<uint64_t>(f[0], "POINT3D_ID", at);
    static const char* const kXyz[] = {"X", "Y", "Z"};
    for (int k = 0; k < 3; ++k) point.xyz[k] = parse_number(f[1 + k], kXyz[k], at);
    for (int k = 4; k < 7; ++k) parse_integer<uint8_t>(f[k], "a colour (0 to 255)", at);
    parse_number(f[7], "ERROR", at);
    point.image_ids.reserve((f.size() - 8) / 2);
    for (size_t k = 8; k < f.size(); k += 2) {
      point.image_ids.push_back(parse_integer<uint32_t>(f[k], "a track's IMAGE_ID", at));
      parse_integer<uint32_t>(f[k + 1], "a track's POINT2D_IDX", at);
    }
    points.push_back(std::move(point));
  }
  return points;
}

std::vector<ColmapPoint> parse_colmap_points_binary(std::string_view bytes, const std::string& where) {
  ByteReader in(bytes, where, "point");
  const uint64_t count = in.u64("the number of points");
  // id, xyz, rgb, error, track length.
  in.check_count(count, 8 + 24 + 3 + 8 + 8, "the number of points");
  std::vector<ColmapPoint> points;
  points.reserve(count);
  for (uint64_t i = 0; i < count; ++i) {
    in.set_record(i, count);
    ColmapPoint point;
    point.id = in.u64("POINT3D_ID");
    for (double& v : point.xyz) v = in.f64("the position");
    in.skip(3, "the colour");
    in.f64("ERROR");
    const uint64_t track_length = in.u64("the track length");
    in.check_count(track_length, 8, "the track length");
    point.image_ids.reserve(track_length);
    for (uint64_t k = 0; k < track_length; ++k) {
      point.image_ids.push_back(in.u32("a track's IMAGE_ID"));
      in.u32("a track's POINT2D_IDX");
    }
    points.push_back(std::move(point));
  }
  in.check_end();
  return points;
}

// ---- the model ----

std::string ColmapModel::file(const char* stem) const {
  return (fs::path(dir) / (std::string(stem) + (binary ? ".bin" : ".txt"))).string();
}

std::string ColmapModel::where(const char* stem, uint64_t line, const char* kind, uint64_t id) const {
  return (line > 0 ? line_at(file(stem), line) : file(stem)) + ": " + kind + " " + std::to_string(id);
}

void check_colmap_model(const ColmapModel& model) {
  std::unordered_set<uint32_t> camera_ids;
  for (const auto& camera : model.cameras) {
    if (!camera_ids.insert(camera.id).second) {
      throw Error(model.where("cameras", camera.line, "camera", camera.id) + " is listed twice");
    }
  }
  if (model.images.empty()) {
    throw Error(model.file("images") + ": no images: the model registered none (did COLMAP's mapper succeed?)");
  }
  std::unordered_set<uint32_t> image_ids;
  std::unordered_set<std::string> names;
  for (const auto& image : model.images) {
    const std::string at = model.where("images", image.line, "image", image.id);
    if (!image_ids.insert(image.id).second) throw Error(at + " is listed twice");
    if (!names.insert(image.name).second) throw Error(at + ": the name '" + image.name + "' is listed twice");
    if (!camera_ids.count(image.camera_id)) {
      throw Error(at + " (" + image.name + ") refers to camera " + std::to_string(image.camera_id) + ", which " +
                  fs::path(model.file("cameras")).filename().string() + " does not list");
    }
  }
  std::unordered_set<uint64_t> point_ids;
  for (const auto& point : model.points) {
    const std::string at = model.where("points3D", point.line, "point", point.id);
    if (!point_ids.insert(point.id).second) throw Error(at + " is listed twice");
    for (uint32_t image_id : point.image_ids) {
      if (!image_ids.count(image_id)) {
        throw Error(at + ": its track names image " + std::to_string(image_id) + ", which " +
                    fs::path(model.file("images")).filename().string() + " does not list");
      }
    }
  }
}

ColmapModel read_colmap_model(const std::string& sparse_dir) {
  std::error_code ec;
  if (!fs::is_directory(sparse_dir, ec)) throw Error(sparse_dir + ": no such folder (expected a COLMAP sparse model)");
  static const char* const kStems[] = {"cameras", "images", "points3D"};
  auto present = [&](const char* extension) {
    std::vector<std::string> found;
    for (const char* stem : kStems) {
      if (fs::is_regular_file(fs::path(sparse_dir) / (std::string(stem) + extension), ec)) {
        found.push_back(std::string(stem) + extension);
      }
    }
    return found;
  };
  const auto bin = present(".bin"), txt = present(".txt");
  ColmapModel model;
  model.dir = sparse_dir;
  if (bin.size() == 3) {
    model.binary = true;
  } else if (txt.size() == 3) {
    model.binary = false;
  } else {
    std::string found;
    for (const auto* list : {&bin, &txt}) {
      for (const auto& name : *list) found += (found.empty() ? "" : ", ") + name;
    }
    const bool has_subfolder_0 = fs::is_directory(fs::path(sparse_dir) / "0", ec);
    throw Error(sparse_dir + ": no COLMAP sparse model: expected cameras, images and points3D (.bin or .txt), found " +
                (found.empty() ? std::string("none of them") : found) +
                (has_subfolder_0 ? " (COLMAP's mapper writes its models to sparse/0, sparse/1, ...: give one)" : ""));
  }
  auto contents = [&](const char* stem) { return io::read_file_text(model.file(stem)); };
  if (model.binary) {
    model.cameras = parse_colmap_cameras_binary(contents("cameras"), model.file("cameras"));
    model.images = parse_colmap_images_binary(contents("images"), model.file("images"));
    model.points = parse_colmap_points_binary(contents("points3D"), model.file("points3D"));
  } else {
    model.cameras = parse_colmap_cameras_text(contents("cameras"), model.file("cameras"));
    model.images = parse_colmap_images_text(contents("images"), model.file("images"));
    model.points = parse_colmap_points_text(contents("points3D"), model.file("points3D"));
  }
  check_colmap_model(model);
  return model;
}

}  // namespace mipnerf::data
