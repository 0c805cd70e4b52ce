// Intrinsics as transforms files give them: fl_x, fl_y, cx, cy, w, h (global or per frame), or camera_angle_x (and
// camera_angle_y) as the Blender files do; and a lens: "camera_model" (a row of core/lens_models.hpp, as nerfstudio
// writes them) with the coefficients that row takes, or instant-ngp's "is_fisheye" and k1, k2, p1, p2.
#pragma once

#include <optional>
#include <string>

#include "core/camera.hpp"
#include "io/json.hpp"

namespace mipnerf::data {

// What a file says about a camera's intrinsics; unset values come from the image or the fallbacks below.
struct IntrinsicsSpec {
  std::optional<double> focal_x_px, focal_y_px;  // "fl_x", "fl_y"
  std::optional<double> center_x_px, center_y_px;  // "cx", "cy": pixels from the left / top edge
  std::optional<double> width_px, height_px;  // "w", "h": the image size the values above refer to
  std::optional<double> camera_angle_x, camera_angle_y;  // full horizontal / vertical field of view, radians
  std::optional<Lens> lens;  // the lens (core/lens.hpp); none: a pinhole camera
};

// Reads the keys above from `object` on top of `base` (a frame's values override the file's global ones).
// Throws mipnerf::Error naming `where` for a non-number or non-positive value, a camera_model not read here
// (FOV, EQUIRECTANGULAR, …), or coefficients the model does not take.
IntrinsicsSpec read_intrinsics(const io::Json& object, const IntrinsicsSpec& base, const std::string& where);

// Sets camera's focal lengths, principal point and size for an image of width × height pixels:
//   fl_x, else 0.5·w / tan(0.5·camera_angle_x) (the Blender loader's formula); fl_y, else
//   0.5·h / tan(0.5·camera_angle_y), else fl_x; cx, cy default to the image centre w/2, h/2.
// Declared w/h must equal the image size. Throws naming `where` when no focal length can be found.
void resolve_intrinsics(const IntrinsicsSpec& spec, uint32_t width, uint32_t height, Camera& camera,
                        const std::string& where);

// The transforms-file keys of a lens (nerfstudio's: camera_model and the coefficients its row takes), empty for a
// pinhole: what read_intrinsics reads back (make-scene's and import-colmap's transforms files, render's camera paths).
io::Json lens_json(const Lens& lens);

// A camera's intrinsics as the transforms keys read_intrinsics reads back: fl_x, fl_y, cx, cy, w, h and its lens. The
// one writer of a camera's intrinsics: camera paths' frames (data/paths/camera_path.hpp) and import-colmap's
// transforms.json go through it.
io::Json intrinsics_json(const Camera& camera);

}  // namespace mipnerf::data
