// The built-in forward-facing scene: the procedural scene in front of a backdrop (a wall and a floor, so every
// ray hits something, as in a photo), seen from a grid of nearly parallel cameras on one side, written in the
// LLFF layout (poses_bounds.npy, images/, images_<factor>/). It tests the LLFF loader, NDC rays and cylinders end
// to end without a download: `mipnerf-cl make-scene OUT --forward-facing`.
#pragma once

#include <string>
#include <vector>

#include "core/camera.hpp"
#include "core/log.hpp"

namespace mipnerf::data {

struct ForwardFacingOptions {
  uint32_t width_px = 256;        // full-resolution images (images/), 4:3; images_<factor>/ are box-downsampled
  uint32_t views_x = 5, views_y = 4;  // the camera grid (LLFF's fern: 20 views)
  uint32_t factor = 4;            // also write images_<factor>/ (the official LLFF default); 1: images/ only
  uint64_t seed = 0;              // sub-pixel jitter
  uint32_t samples_per_axis = 4;  // jittered supersampling per pixel
  unsigned threads = 0;           // 0: every hardware thread
  double camera_angle_x = 0.87;   // horizontal field of view, radians (50°)
  double grid_width = 1.2;        // the camera grid's width in scene units (its height: half), 4 from the scene's
                                  // centre: neighbours ~4° apart; narrower, a capture of small parallax
  bool jpeg = false;              // write the images as JPEG (quality 95), as a phone capture holds them; else PNG
  Lens lens;                      // photos through this lens: written as OUT/transforms.json (LLFF holds pinholes)
};

// Checks sizes and counts; throws mipnerf::Error saying what to change.
void validate(const ForwardFacingOptions& options);
// The cameras, full resolution, OpenGL axes, row by row of the grid; near/far = the depths they see.
std::vector<Camera> forward_facing_cameras(const ForwardFacingOptions& options);
// Writes OUT/poses_bounds.npy, OUT/images/image<k>.png and OUT/images_<factor>/image<k>.png (RGB, no alpha; .jpg
// with options.jpeg). Behind a lens (options.lens), OUT/transforms.json instead of poses_bounds.npy and no
// images_<factor>/: what `dataset import-colmap` writes for a forward-facing capture with a lens (intrinsics and lens,
// near/far over every view).
void write_forward_facing_scene(const std::string& out_dir, const ForwardFacingOptions& options, const LogFn& log = {});

}  // namespace mipnerf::data
