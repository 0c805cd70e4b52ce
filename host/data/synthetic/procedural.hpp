// The built-in procedural scene: an analytic scene with fine, high-contrast detail (a checkered sphere,
// striped boxes and a checkered slab) ray-traced on the CPU in double precision with jittered supersampling,
// so its ground truth is properly anti-aliased. `mipnerf-cl make-scene OUT` writes it in the Blender format
// (RGBA PNGs, transforms_{train,val,test}.json with near/far) plus OUT/multiscale (metadata.json). It is the
// quick-start scene and the tests' fixture, and needs no download.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/log.hpp"
#include "core/camera.hpp"
#include "data/image.hpp"
#include "io/json.hpp"

namespace mipnerf::data {

struct SceneOptions {
  uint32_t size_px = 64;          // square images, size_px × size_px at full resolution
  uint32_t train_views = 40;      // random views on the upper hemisphere
  uint32_t val_views = 8;         // an orbit at 25° elevation
  uint32_t test_views = 8;        // an orbit at 40° elevation, between the val azimuths
  int scales = 4;                 // > 1: also write OUT/multiscale with ×2 … ×2^(scales−1); size_px must divide
  uint64_t seed = 0;              // camera placement and sub-pixel jitter: the same seed gives the same bytes
  uint32_t samples_per_axis = 8;  // jittered supersampling: samples_per_axis² rays per pixel, one per stratum
  unsigned threads = 0;           // render threads; 0 = every hardware thread
  double camera_angle_x = 0.6911112070083618;  // horizontal field of view (radians), as the Blender scenes'
  double camera_distance = 4.0;   // cameras on a sphere of this radius around the origin, looking at it
  double near = 2.0, far = 6.0;   // the scene lies within 1.5 of the origin: depths 2.5 … 5.5
  Lens lens;                      // every camera behind this lens (pinhole: none); written into the transforms files
};

// A camera of a built-in scene: a pinhole of width × height pixels with the horizontal field of view angle_x
// (radians), square pixels, the principal point at the image centre, placed by camera_to_world; near/far and lens are
// the caller's.
Camera centred_pinhole(const std::array<double, 12>& camera_to_world, uint32_t width_px, uint32_t height_px,
                       double angle_x);

// Checks the options (sizes, counts, scales dividing the size); throws mipnerf::Error saying what to change.
void validate(const SceneOptions& options);

// The cameras of "train", "val" or "test" at full resolution (deterministic in options.seed).
std::vector<Camera> procedural_cameras(const std::string& split, const SceneOptions& options);

// What one ray sees: the first surface hit (t in units of the ray's direction) and its shaded colour.
struct SceneHit {
  bool hit = false;
  double t = 0.0;
  std::array<double, 3> rgb{0.0, 0.0, 0.0};
};
SceneHit trace_procedural(const Ray& ray);

// One view: straight RGBA in [0, 1]; each pixel averages samples_per_axis² jittered rays (camera_ray):
// alpha = the fraction that hit, rgb = the mean colour of those that hit (0 where none did). `view_key`
// makes the jitter of each view distinct.
RgbaImage render_procedural(const Camera& camera, const SceneOptions& options, uint32_t view_key);
// The same renderer over any scene `trace` describes (the forward-facing scene adds a backdrop).
RgbaImage render_traced(const Camera& camera, const SceneOptions& options, uint32_t view_key,
                        SceneHit (*trace)(const Ray&));

// Writes the whole scene to `out_dir` (created if needed); logs progress through `log`.
void write_procedural_scene(const std::string& out_dir, const SceneOptions& options, const LogFn& log = {});

}  // namespace mipnerf::data
