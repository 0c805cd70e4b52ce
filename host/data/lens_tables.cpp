// Per-camera lens tables: undistorted pixel centres and footprint radii, in double precision.
#include "data/lens_tables.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <tuple>

#include "core/error.hpp"

namespace mipnerf::data {
namespace {

constexpr double kRadiusPerPixelWidth = 0.57735026918962576451;  // 2/√12

using TableKey = std::tuple<int, double, double, double, double, double, double, double, double, double, double,
                            uint32_t, uint32_t>;

TableKey key_of(const Camera& c) {
  const Lens& l = c.lens;
  return {static_cast<int>(l.model), l.k1, l.k2, l.k3, l.k4, l.p1, l.p2, c.focal_x_px, c.focal_y_px, c.center_x_px,
          c.center_y_px, c.width_px, c.height_px};
}

std::string fold_error(const Camera& c, const std::string& name, uint32_t x, uint32_t y) {
  return name + ": its " + lens_model_name(c.lens.model) + " lens cannot be inverted at pixel (" + std::to_string(x) +
         ", " + std::to_string(y) + "): no ray leaves the lens there (the distortion folds the image, or the pixel "
         "lies beyond the lens's field); check the coefficients (a lens COLMAP estimates is invertible over its "
         "image)";
}

// Appends camera `c`'s table: the undistorted centre of every pixel, then each pixel's radius from its neighbours.
void append_table(const Camera& c, const std::string& name, std::vector<float>& values) {
  const uint32_t w = c.width_px, h = c.height_px;
  std::vector<Uv> centre(static_cast<size_t>(w) * h);
  for (uint32_t y = 0; y < h; ++y) {
    for (uint32_t x = 0; x < w; ++x) {
      const Uv distorted = {(x + 0.5 - c.center_x_px) / c.focal_x_px, (y + 0.5 - c.center_y_px) / c.focal_y_px};
      if (!undistort(c.lens, distorted, centre[static_cast<size_t>(y) * w + x])) throw Error(fold_error(c, name, x, y));
    }
  }
  auto at = [&](uint32_t x, uint32_t y) { return centre[static_cast<size_t>(y) * w + x]; };
  auto distance = [](const Uv& a, const Uv& b) { return std::hypot(a[0] - b[0], a[1] - b[1]); };
  for (uint32_t y = 0; y < h; ++y) {
    for (uint32_t x = 0; x < w; ++x) {
      const Uv here = at(x, y);
      const double across = w > 1 ? distance(here, at(x + 1 < w ? x + 1 : x - 1, y)) : 1.0 / c.focal_x_px;
      const double down = h > 1 ? distance(here, at(x, y + 1 < h ? y + 1 : y - 1)) : 1.0 / c.focal_y_px;
      values.push_back(static_cast<float>(here[0]));
      values.push_back(static_cast<float>(here[1]));
      values.push_back(static_cast<float>(0.5 * (across + down) * kRadiusPerPixelWidth));
      values.push_back(0.0f);
    }
  }
}

}  // namespace

LensTables build_lens_tables(const std::vector<Camera>& cameras, const std::vector<std::string>& names) {
  LensTables tables;
  tables.table_of.assign(cameras.size(), 0);
  std::map<TableKey, uint32_t> made;  // a table per distinct lens, intrinsics and size
  for (size_t c = 0; c < cameras.size(); ++c) {
    const Camera& camera = cameras[c];
    if (camera.lens.is_pinhole()) continue;
    const std::string name = c < names.size() ? names[c] : "camera " + std::to_string(c);
    check_lens(camera.lens, name);
    const auto [found, fresh] = made.emplace(key_of(camera), static_cast<uint32_t>(tables.values.size() / 4 + 1));
    if (fresh) {
      if (tables.values.size() / 4 + static_cast<size_t>(camera.width_px) * camera.height_px >= 0xFFFFFFFFu) {
        throw Error(name + ": the lens tables would exceed 2^32 pixels; use fewer distinct lens sizes");
      }
      append_table(camera, name, tables.values);
    }
    tables.table_of[c] = found->second;
  }
  return tables;
}

void check_lens_over_image(const Camera& c, const std::string& name) {
  if (c.lens.is_pinhole()) return;
  check_lens(c.lens, name);
  auto visit = [&](uint32_t x, uint32_t y) {
    const Uv distorted = {(x + 0.5 - c.center_x_px) / c.focal_x_px, (y + 0.5 - c.center_y_px) / c.focal_y_px};
    Uv uv;
    if (!undistort(c.lens, distorted, uv)) throw Error(fold_error(c, name, x, y));
  };
  const uint32_t w = c.width_px, h = c.height_px;
  for (uint32_t x = 0; x < w; ++x) {
    visit(x, 0);
    visit(x, h - 1);
    visit(x, h / 2);
  }
  for (uint32_t y = 0; y < h; ++y) {
    visit(0, y);
    visit(w - 1, y);
    visit(w / 2, y);
  }
}

void set_lens_table_slots(std::vector<float>& packed, const LensTables& tables) {
  for (size_t c = 0; c < tables.table_of.size(); ++c) {
    std::memcpy(&packed[c * camera_layout::stride + camera_layout::lens_table], &tables.table_of[c], sizeof(float));
  }
}

double largest_distortion_px(const Camera& c) {
  if (c.lens.is_pinhole()) return 0.0;
  double largest = 0.0;
  auto visit = [&](double x, double y) {
    const Uv u = {(x - c.center_x_px) / c.focal_x_px, (y - c.center_y_px) / c.focal_y_px};
    Uv undistorted;
    if (!undistort(c.lens, u, undistorted)) return;
    largest = std::max(largest, std::hypot((undistorted[0] - u[0]) * c.focal_x_px, (undistorted[1] - u[1]) * c.focal_y_px));
  };
  const int n = 64;
  for (int k = 0; k <= n; ++k) {
    const double x = c.width_px * k / static_cast<double>(n), y = c.height_px * k / static_cast<double>(n);
    visit(x, 0);
    visit(x, c.height_px);
    visit(0, y);
    visit(c.width_px, y);
    visit(x, 0.5 * c.height_px);
    visit(0.5 * c.width_px, y);
  }
  return largest;
}

}  // namespace mipnerf::data
