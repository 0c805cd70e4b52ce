// COLMAP sparse model → a dataset load_dataset reads, in the layout the cameras call for:
//  - a forward-facing capture (every optical axis within 45° of their mean, data::looks_forward) of one pinhole camera
//    becomes an LLFF capture, as LLFF's own imgs2poses makes one from a COLMAP model: OUT/poses_bounds.npy (poses in
//    LLFF's axes, h, w, focal; per image the 0.1th and 99.9th percentile depth of the points it sees) and OUT/images/
//    (links to the registered photos, in pose order). It then trains as an LLFF capture does: NDC rays, cylinders,
//    and every official LLFF convention (data/formats/llff_capture.hpp).
//  - anything else becomes OUT/transforms.json: poses converted from COLMAP's world-to-camera (OpenCV axes) to
//    camera-to-world in OpenGL/Blender axes, the world recentred and rescaled, pinhole intrinsics per camera,
//    near/far from the sparse points' depths, and OUT/images/ (links to the registered photos) that its frames name:
//    a dataset names only files inside its folder (data/path_policy.hpp).
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "data/import/colmap_model.hpp"
#include "data/pose.hpp"

namespace mipnerf::data {

// The near/far rule (see near_far_from_depths): percentiles of each image's point depths, then a margin.
constexpr double kDepthPercentileLow = 0.01;
constexpr double kDepthPercentileHigh = 0.99;
constexpr double kNearMargin = 0.9;
constexpr double kFarMargin = 1.1;
// The imported world is scaled so that the median camera sits this far from the scene centre: the distance of
// the Blender scenes' and the procedural scene's cameras, for which the defaults (near 2, far 6, the positional
// encoding's frequencies) were chosen.
constexpr double kImportedCameraDistance = 4.0;

// COLMAP's pose (x_camera = R(q) x_world + t, camera axes x right, y down, z forward) as a camera-to-world matrix in
// OpenGL/Blender camera axes (x right, y up, looking down −z): rotation Rᵀ with its y and z columns negated, centre
// −Rᵀt. q = (qw, qx, qy, qz), unit length.
Matrix34 colmap_camera_to_world(const std::array<double, 4>& qvec, const std::array<double, 3>& tvec);

// Depth (z in COLMAP's camera frame, i.e. distance along the optical axis) of a world point in an image.
double colmap_depth(const ColmapImage& image, const Vec3& point_world);

// Near/far from the depths of the sparse points each image sees (only points in front of it, depth > 0):
// per image the kDepthPercentileLow and kDepthPercentileHigh percentiles (linear interpolation between sorted
// depths), then near = kNearMargin × the smallest, far = kFarMargin × the largest over the images. Empty when no
// image has a depth. The vectors are sorted in place.
struct DepthRange {
  double near = 0, far = 0;
  size_t images = 0;  // images that had depths
};
std::optional<DepthRange> near_far_from_depths(std::vector<std::vector<double>>& depths_per_image);

// Per image of model.images (same order), how many of the sparse points it sees lie in front of it (depth > 0).
// COLMAP can register an image whose points all end up behind it or filtered away (its mapper with the settings for
// small baselines did, 1 photo of 12 in one run of the test suite): no point checks such a pose, and an LLFF
// capture cannot take that image's depth bounds from its points. An image needs kMinPointsInFront of them.
std::vector<size_t> points_in_front_counts(const ColmapModel& model);
constexpr size_t kMinPointsInFront = 2;

// The layout an import writes: chosen from the cameras (automatic), or forced.
enum class ImportLayout { automatic, llff, transforms_json };

struct ColmapImportOptions {
  // Override the near/far chosen from the points, in the imported scene's units (after recentring and scaling).
  // transforms.json only: an LLFF capture's bounds are per image, and its loader rescales them itself.
  std::optional<double> near, far;
  ImportLayout layout = ImportLayout::automatic;
  // Images of the model not imported, by name (from-photos: those that see fewer than kMinPointsInFront points).
  std::vector<std::string> leave_out;
};

// What import_colmap wrote.
struct ColmapImport {
  ImportLayout layout = ImportLayout::transforms_json;  // what was written (never automatic)
  std::string layout_reason;                   // why that layout, for people
  std::string dataset_path;                    // what `train --data` takes: OUT (LLFF) or OUT/transforms.json
  std::string transforms_path;                 // OUT/transforms.json (transforms.json layout)
  bool binary = true;                          // the model's format
  size_t images = 0, cameras = 0, points = 0;  // cameras: the intrinsics the images use
  std::vector<std::string> camera_models;      // their models, e.g. "PINHOLE"
  double near = 0, far = 0;                    // written, scene units
  bool near_far_from_points = true;            // false: both given in the options
  Vec3 centre{};                               // the COLMAP world point that became the origin
  std::string centre_rule;                     // "look-at", "points" or "cameras" (see import_colmap)
  double scale = 1.0;                          // scene units per COLMAP unit
};

// Reads the model in sparse_dir, resolves every image in images_dir (its name, or the name with the extension
// replaced by .png: the loader reads PNG only) and checks its size against its camera, then writes
// out_dir/transforms.json. Frames are in image-name order (the loader holds out every 8th as test).
//
// World: x_scene = scale · (x_colmap − centre), rotation unchanged. COLMAP's world has an arbitrary origin and
// unit, but the positional encoding sees world positions: far from the origin, float32 loses its low bits and
// the encoding's frequencies no longer match the scene's size. So the centre is the look-at point (closest to
// every optical axis, as `dataset inspect` prints it) when it lies in front of every camera within near..far (a
// capture around an object), else the per-axis median of the sparse points (forward-facing captures, whose axes
// meet far away or not at all), else (no points) the mean camera centre; the scale puts the median camera at
// kImportedCameraDistance from it.
//
// Throws mipnerf::Error with one line for: a malformed model (see colmap.hpp), a camera that is not
// SIMPLE_PINHOLE or PINHOLE (saying to run COLMAP's image_undistorter), images missing from images_dir (named),
// images that are neither PNG nor JPEG, an image whose size differs from its camera's, no points to choose near/far
// from, an LLFF layout asked for cameras that do not fit it (saying why), --near/--far with the LLFF layout.
ColmapImport import_colmap(const std::string& sparse_dir, const std::string& images_dir, const std::string& out_dir,
                           const ColmapImportOptions& options = {});

}  // namespace mipnerf::data
