// Writes a traced scene in the LLFF layout, as the built-in forward-facing and unbounded (360°) scenes are written:
// OUT/images/<name> at full resolution, OUT/images_<factor>/<name> box-downsampled, and OUT/poses_bounds.npy (per view
// LLFF's 3×5 [down, right, backwards, position, (h, w, focal)] and the view's near and far).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "core/log.hpp"
#include "data/synthetic/procedural.hpp"

namespace mipnerf::data {

struct LlffWriteOptions {
  uint32_t factor = 4;            // also write images_<factor>/ (1: images/ only)
  bool jpeg = false;              // JPEG (quality 95), as a phone capture holds them; else PNG
  uint64_t seed = 0;              // sub-pixel jitter
  uint32_t samples_per_axis = 4;  // jittered supersampling per pixel
  unsigned threads = 0;           // 0: every hardware thread
  uint32_t view_key_base = 0;     // view k draws its jitter as view key view_key_base + k
};

// The writer's settings from a built-in capture's options (their fields of the same names), view keys from
// view_key_base.
template <typename CaptureOptions>
LlffWriteOptions llff_write_options(const CaptureOptions& capture, uint32_t view_key_base) {
  LlffWriteOptions write;
  write.factor = capture.factor;
  write.jpeg = capture.jpeg;
  write.seed = capture.seed;
  write.samples_per_axis = capture.samples_per_axis;
  write.threads = capture.threads;
  write.view_key_base = view_key_base;
  return write;
}

// The depths (t) of the surfaces a camera sees along a 32 × 24 grid of rays through `trace`, sorted; misses and the
// sky (t = +∞) left out. What a capture's bounds are chosen from, as COLMAP's sparse points would give them.
std::vector<double> traced_depths(const Camera& camera, SceneHit (*trace)(const Ray&));

// "image007.png" (or .jpg): the name of view k.
std::string llff_image_name(size_t k, bool jpeg);

// Renders every camera through `trace` (render_traced: RGB, no alpha written; through each camera's lens) into
// OUT/images/ and OUT/images_<factor>/, named by llff_image_name.
void write_view_images(const std::string& out_dir, const std::vector<Camera>& cameras, SceneHit (*trace)(const Ray&),
                       const LlffWriteOptions& options);

// write_view_images, then OUT/poses_bounds.npy: the capture in the LLFF layout; cameras carry their near and far.
void write_llff_views(const std::string& out_dir, const std::vector<Camera>& cameras, SceneHit (*trace)(const Ray&),
                      const LlffWriteOptions& options);

}  // namespace mipnerf::data
