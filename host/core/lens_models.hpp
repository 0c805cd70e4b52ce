// The lens models mipnerf-cl reads, one row each: COLMAP's name and id, where its parameter list puts the focal
// lengths and principal point, and its distortion coefficients in COLMAP's order (src/colmap/sensor/models.h). Every
// reader and writer of a lens goes through these rows — transforms files (nerfstudio's keys), COLMAP models,
// `make-scene --lens`, `dataset inspect`, `from-photos --camera-model` — and every message that lists the models
// reads them from here. A new lens model is a row in lens_models.cpp, its enum value and its math in lens.hpp/.cpp.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "core/lens.hpp"

namespace mipnerf {

// One coefficient: its name (COLMAP's and nerfstudio's transforms key) and where Lens holds it.
struct LensCoefficient {
  const char* name;
  double Lens::*value;
};

struct LensRow {
  const char* colmap_name;  // "OPENCV"
  int colmap_id;            // COLMAP's model id (cameras.bin)
  LensModel model;
  bool single_focal;        // the parameters start f, cx, cy (else fx, fy, cx, cy)
  std::vector<LensCoefficient> coefficients;  // after the focal lengths and principal point, COLMAP's order
  size_t intrinsic_count() const { return single_focal ? 3 : 4; }
  size_t parameter_count() const { return intrinsic_count() + coefficients.size(); }
  bool takes(std::string_view coefficient) const;
};

const std::vector<LensRow>& lens_rows();

// The row named `colmap_name` ("OPENCV"), or null when mipnerf-cl does not read that model.
const LensRow* find_lens_row(std::string_view colmap_name);

// The row of `model`; for the pinhole, PINHOLE (two focal lengths: every camera writes as it).
const LensRow& lens_row(LensModel model);

// Every coefficient name any row takes ("k1", "k2", …, each once, in first-seen order): the transforms keys of a lens.
const std::vector<std::string>& lens_coefficient_names();

// "SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, OPENCV_FISHEYE and FULL_OPENCV", for messages; `join`
// before the last name ("and", "or").
std::string lens_model_list(const char* join = "and");

// "SIMPLE_RADIAL: k1; RADIAL: k1, k2; …" over the rows that take coefficients, for messages.
std::string lens_coefficient_list();

// A lens's coefficients in its row's order.
std::vector<double> lens_coefficients(const Lens& lens);

// The lens of `row` with `coefficients` in its order. Throws mipnerf::Error naming `where` when their count is not
// the row's.
Lens make_lens(const LensRow& row, const std::vector<double>& coefficients, const std::string& where);

// A COLMAP camera's parameter list read through its row.
struct ColmapIntrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  Lens lens;
};
// Throws mipnerf::Error naming `where` when the parameter count is not the row's.
ColmapIntrinsics read_colmap_params(const LensRow& row, const std::vector<double>& params, const std::string& where);

}  // namespace mipnerf
