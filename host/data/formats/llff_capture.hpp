// LLFF captures (forward-facing photos, as in the NeRF and mip-NeRF papers): DIR/poses_bounds.npy and DIR/images/
// (or DIR/images_<factor>/), read with the official conventions (google/mipnerf datasets.py, class LLFF, and
// configs/llff.gin): axes reordered to OpenGL's, poses and bounds rescaled so the nearest bound is 1/0.75, poses
// recentred on their average, every 8th image held out for testing; rays in NDC with near 0 and far 1 (cast as
// cylinders), or, for a 360° capture (`spherify`), world rays between the rescaled bounds.
#pragma once

#include <string>
#include <vector>

#include "core/camera.hpp"
#include "data/dataset.hpp"
#include "data/pose.hpp"

namespace mipnerf::data {

// The poses of an LLFF capture after the official transformations, before any split.
struct LlffCapture {
  std::string dir;
  std::vector<Matrix34> camera_to_world;      // [N], OpenGL axes (x right, y up, looking down −z)
  std::vector<std::array<double, 2>> bounds;  // [N] near, far scene depth of each view, rescaled
  double focal_px = 0;            // focal length for the images in image_dir
  uint32_t width_px = 0, height_px = 0;  // poses_bounds.npy's full-resolution size (h, w of its hwf column)
  std::string image_dir;          // DIR/images_<factor> when present, else DIR/images
  uint32_t stored_factor = 1;     // the factor image_dir already has (1: DIR/images, downsampled on load)
  std::vector<std::string> image_files;  // [N], sorted by name, as the official loader lists them
  bool spherify = false;
};

// DIR holds an LLFF capture (poses_bounds.npy).
bool is_llff_folder(const std::string& dir);

// Reads DIR/poses_bounds.npy and lists the images; options.factor picks DIR/images_<factor> when it exists;
// options.llff.spherify re-poses a 360° capture. Throws mipnerf::Error naming the file for a malformed array (not N×17,
// non-finite, non-positive bounds, a non-rigid pose) and for an image count that differs from N.
LlffCapture read_llff(const std::string& dir, const LoadOptions& options);

// Whether the capture looks inward from all around (a 360° capture, to spherify) rather than forward: its views'
// optical axes spread over more than 90°.
bool looks_360(const LlffCapture& capture);

// The official spiral (_generate_spiral_poses) around recentred forward-facing poses (their average pose near the
// identity, as LLFF's and NDC's world has it): two turns of `frames` views, radii from the 90th percentile of |position|
// per axis, focused at the mean disparity depth between 0.9 × nearest_depth and 5 × farthest_depth.
std::vector<Matrix34> spiral_poses(const std::vector<Matrix34>& camera_to_world, double nearest_depth,
                                   double farthest_depth, int frames);

// The official render path: for a forward-facing capture the spiral (two turns, `frames` views, radii from the
// 90th percentile of camera positions, focused at the capture's mean disparity depth), for a spherified one the
// circle at the cameras' height. Cameras at the capture's focal length and image size (image_dir), NDC/world near
// and far as the loader gives them.
std::vector<Camera> llff_render_path(const LlffCapture& capture, const LoadOptions& options, int frames);

}  // namespace mipnerf::data
