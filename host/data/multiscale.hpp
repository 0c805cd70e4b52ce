// The paper's multiscale Blender dataset on disk: `mipnerf-cl make-multiscale IN OUT` (training can also
// build the same pyramid on the fly: LoadOptions::scales).
#pragma once

#include <string>

#include "core/log.hpp"

namespace mipnerf::data {

// Reads the dataset at `in_path` (Blender folder or transforms.json; every split present) and writes OUT as
// mip-NeRF's scripts/convert_blender_data.py does: OUT/images_<split>/NNN_dJ.png, image NNN box-downsampled
// ×2^J (J = 0 … scales − 1, the straight RGBA averaged, see downsample2), still RGBA, at the input's bit
// depth (rounded to nearest; the official script truncates), and OUT/metadata.json holding per image
// file_path, cam2world (4×4), width, height, focal (fl_x / 2^J), label (J), near, far, lossmult (4^J) and
// pix2cam (the inverse intrinsics, which also carry fl_y, cx and cy). `scales` is 1 … 8 (the paper: 4).
void write_multiscale(const std::string& in_path, const std::string& out_dir, int scales, const LogFn& log = {});

}  // namespace mipnerf::data
