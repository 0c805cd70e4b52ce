// The multiscale Blender format's parser: metadata.json (the official convert_blender_data.py's columns) into frames,
// each image at its scale with its lossmult; the row is multiscale_blender.cpp.
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/error.hpp"
#include "data/formats/formats.hpp"
#include "data/frames.hpp"
#include "data/intrinsics.hpp"
#include "io/json.hpp"

namespace mipnerf::data {
namespace fs = std::filesystem;

namespace detail {
namespace {

double array_number(const io::Json& array, size_t i, const std::string& key, const std::string& where) {
  const auto& value = array[i];
  if (!value.is_number() || !std::isfinite(value.get<double>())) {
    throw Error(where + ": '" + key + "' must hold finite numbers, got " + io::json_type_name(value));
  }
  return value.get<double>();
}

// pix2cam = [[1/fx, 0, −cx/fx], [0, −1/fy, cy/fy], [0, 0, −1]] (official multiscale loader): back to fx, fy, cx, cy.
void intrinsics_from_pix2cam(const io::Json& m, IntrinsicsSpec& spec, const std::string& where) {
  const std::string shape = where + ": 'pix2cam' entries must be 3x3 arrays of numbers";
  if (!m.is_array() || m.size() != 3) throw Error(shape);
  double k[3][3];
  for (int r = 0; r < 3; ++r) {
    if (!m[r].is_array() || m[r].size() != 3) throw Error(shape);
    for (int c = 0; c < 3; ++c) k[r][c] = array_number(m[r], c, "pix2cam", where);
  }
  if (!(k[0][0] > 0.0) || !(k[1][1] < 0.0) || k[2][2] != -1.0 || k[0][1] != 0.0 || k[1][0] != 0.0) {
    throw Error(where + ": 'pix2cam' is not a pinhole inverse [[1/fx,0,-cx/fx],[0,-1/fy,cy/fy],[0,0,-1]]");
  }
  spec.focal_x_px = 1.0 / k[0][0];
  spec.focal_y_px = -1.0 / k[1][1];
  spec.center_x_px = -k[0][2] * *spec.focal_x_px;
  spec.center_y_px = k[1][2] * *spec.focal_y_px;
}

}  // namespace

std::vector<SplitSpec> parse_multiscale_metadata(const std::string& file, const LoadOptions& options) {
  const io::Json root = io::read_json(file);
  io::require_object(root, file);
  const std::string base_dir = fs::path(file).parent_path().string();
  std::vector<SplitSpec> splits;
  for (const auto& name : wanted_splits(options)) {
    if (!root.contains(name)) {
      if (options.splits.empty()) continue;
      throw Error(file + ": no split '" + name + "'");
    }
    const std::string where = file + ": " + name;
    const io::Json& meta = io::require_object(root.at(name), where);
    const auto& paths = io::require_array(meta, "file_path", where);
    const size_t n = paths.size();
    if (n == 0) throw Error(where + ": 'file_path' is empty: the split has no images");
    auto column = [&](const char* key, bool required) -> const io::Json* {
      if (!required && !meta.contains(key)) return nullptr;
      const auto& array = io::require_array(meta, key, where);
      if (array.size() != n) {
        throw Error(where + ": '" + key + "' has " + std::to_string(array.size()) + " entries but 'file_path' has " +
                    std::to_string(n));
      }
      return &array;
    };
    const io::Json* cam2world = column("cam2world", true);
    const io::Json* width = column("width", true);
    const io::Json* height = column("height", true);
    const io::Json* pix2cam = column("pix2cam", false);
    const io::Json* focal = pix2cam ? column("focal", false) : column("focal", true);
    const io::Json* lossmult = column("lossmult", false);
    const io::Json* label = column("label", false);
    const io::Json* near = column("near", false);
    const io::Json* far = column("far", false);

    SplitSpec split;
    split.name = name;
    split.source = file;
    split.uniform_size = false;
    for (size_t i = 0; i < n; ++i) {
      FrameSpec frame;
      frame.where = where + "[" + std::to_string(i) + "]";
      if (!paths[i].is_string()) throw Error(frame.where + ": 'file_path' entries must be strings");
      frame.camera_to_world = pose_from_json((*cam2world)[i], frame.where);
      frame.intrinsics.width_px = array_number(*width, i, "width", frame.where);
      frame.intrinsics.height_px = array_number(*height, i, "height", frame.where);
      if (pix2cam) {
        intrinsics_from_pix2cam((*pix2cam)[i], frame.intrinsics, frame.where);
      } else {
        const double f = array_number(*focal, i, "focal", frame.where);
        if (!(f > 0.0)) throw Error(frame.where + ": 'focal' must be positive");
        frame.intrinsics.focal_x_px = frame.intrinsics.focal_y_px = f;
      }
      const double level = label ? array_number(*label, i, "label", frame.where) : 0.0;
      if (level < 0 || level > 16 || level != std::floor(level)) {
        throw Error(frame.where + ": 'label' must be a scale level 0, 1, 2, ...");
      }
      frame.scale_level = static_cast<uint32_t>(level);
      frame.lossmult = lossmult ? array_number(*lossmult, i, "lossmult", frame.where) : std::pow(4.0, level);
      if (!(frame.lossmult > 0.0)) throw Error(frame.where + ": 'lossmult' must be positive");
      frame.near = options.near ? *options.near : near ? array_number(*near, i, "near", frame.where) : 2.0;
      frame.far = options.far ? *options.far : far ? array_number(*far, i, "far", frame.where) : 6.0;
      if (!(frame.near >= 0.0) || !(frame.far > frame.near)) throw Error(frame.where + ": need 0 <= near < far");
      frame.image_path = resolve_image_path(base_dir, paths[i].get<std::string>(), frame.where);
      split.frames.push_back(std::move(frame));
    }
    splits.push_back(std::move(split));
  }
  return splits;
}

}  // namespace detail

}  // namespace mipnerf::data
