// The lens models read here, as rows (COLMAP's src/colmap/sensor/models.h: model ids, parameter orders).
#include "core/lens_models.hpp"

#include "core/error.hpp"

namespace mipnerf {

const std::vector<LensRow>& lens_rows() {
  static const std::vector<LensRow> kRows = {
      {"SIMPLE_PINHOLE", 0, LensModel::pinhole, true, {}},
      {"PINHOLE", 1, LensModel::pinhole, false, {}},
      {"SIMPLE_RADIAL", 2, LensModel::simple_radial, true, {{"k1", &Lens::k1}}},
      {"RADIAL", 3, LensModel::radial, true, {{"k1", &Lens::k1}, {"k2", &Lens::k2}}},
      {"OPENCV", 4, LensModel::opencv, false, {{"k1", &Lens::k1}, {"k2", &Lens::k2}, {"p1", &Lens::p1}, {"p2", &Lens::p2}}},
      {"OPENCV_FISHEYE", 5, LensModel::opencv_fisheye, false,
       {{"k1", &Lens::k1}, {"k2", &Lens::k2}, {"k3", &Lens::k3}, {"k4", &Lens::k4}}},
      {"FULL_OPENCV", 6, LensModel::full_opencv, false,
       {{"k1", &Lens::k1}, {"k2", &Lens::k2}, {"p1", &Lens::p1}, {"p2", &Lens::p2}, {"k3", &Lens::k3},
        {"k4", &Lens::k4}, {"k5", &Lens::k5}, {"k6", &Lens::k6}}},
  };
  return kRows;
}

bool LensRow::takes(std::string_view coefficient) const {
  for (const auto& c : coefficients) {
    if (coefficient == c.name) return true;
  }
  return false;
}

const LensRow* find_lens_row(std::string_view colmap_name) {
  for (const auto& row : lens_rows()) {
    if (colmap_name == row.colmap_name) return &row;
  }
  return nullptr;
}

const LensRow& lens_row(LensModel model) {
  for (const auto& row : lens_rows()) {
    if (row.model == model && !(model == LensModel::pinhole && row.single_focal)) return row;
  }
  throw Error("lens model " + std::to_string(static_cast<int>(model)) + " has no row in core/lens_models.cpp");
}

const char* lens_model_name(LensModel model) { return lens_row(model).colmap_name; }

const std::vector<std::string>& lens_coefficient_names() {
  static const std::vector<std::string> kNames = [] {
    std::vector<std::string> names;
    for (const auto& row : lens_rows()) {
      for (const auto& c : row.coefficients) {
        bool seen = false;
        for (const auto& name : names) seen = seen || name == c.name;
        if (!seen) names.push_back(c.name);
      }
    }
    return names;
  }();
  return kNames;
}

std::string lens_model_list(const char* join) {
  const auto& rows = lens_rows();
  std::string text;
  for (size_t i = 0; i < rows.size(); ++i) {
    if (i > 0) text += i + 1 == rows.size() ? std::string(" ") + join + " " : ", ";
    text += rows[i].colmap_name;
  }
  return text;
}

std::string lens_coefficient_list() {
  std::string text;
  for (const auto& row : lens_rows()) {
    if (row.coefficients.empty()) continue;
    text += (text.empty() ? "" : "; ") + std::string(row.colmap_name) + ":";
    for (size_t i = 0; i < row.coefficients.size(); ++i) text += (i ? ", " : " ") + std::string(row.coefficients[i].name);
  }
  return text;
}

std::vector<double> lens_coefficients(const Lens& lens) {
  std::vector<double> values;
  for (const auto& c : lens_row(lens.model).coefficients) values.push_back(lens.*c.value);
  return values;
}

Lens make_lens(const LensRow& row, const std::vector<double>& coefficients, const std::string& where) {
  if (coefficients.size() != row.coefficients.size()) {
    throw Error(where + ": " + row.colmap_name + " takes " + std::to_string(row.coefficients.size()) +
                " coefficients, got " + std::to_string(coefficients.size()));
  }
  Lens lens;
  lens.model = row.model;
  for (size_t i = 0; i < coefficients.size(); ++i) lens.*row.coefficients[i].value = coefficients[i];
  return lens;
}

ColmapIntrinsics read_colmap_params(const LensRow& row, const std::vector<double>& params, const std::string& where) {
  if (params.size() != row.parameter_count()) {
    throw Error(where + ": a " + row.colmap_name + " camera has " + std::to_string(row.parameter_count()) +
                " parameters, got " + std::to_string(params.size()));
  }
  ColmapIntrinsics in;
  in.fx = params[0];
  in.fy = row.single_focal ? params[0] : params[1];
  in.cx = params[row.intrinsic_count() - 2];
  in.cy = params[row.intrinsic_count() - 1];
  const std::vector<double> coefficients(params.begin() + static_cast<long>(row.intrinsic_count()), params.end());
  in.lens = make_lens(row, coefficients, where);
  return in;
}

}  // namespace mipnerf
