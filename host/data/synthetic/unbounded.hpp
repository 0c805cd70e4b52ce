// The built-in unbounded (360°) scene: the procedural scene standing on an endless checkered ground among distant
// pillars under a sky, seen from a full orbit of cameras looking at it, as photos taken walking around a thing
// outdoors. Every ray hits something and depths run from about 2 to infinity (the far ground, the sky): the case
// mip-NeRF 360's contraction exists for (issue 45). Written in the LLFF layout as a COLMAP capture of it would be
// (poses_bounds.npy with each view's bounds from the depths it sees, the sky excluded as sparse points exclude it;
// images/, images_<factor>/): `mipnerf-cl make-scene OUT --unbounded`. The LLFF loader finds it a 360° capture.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "core/log.hpp"
#include "data/synthetic/procedural.hpp"

namespace mipnerf::data {

// The surfaces: the ground's 1-unit checker, the pillars' stripes and the central scene's own (the scene of the
// committed studies), or the ground's and pillars' colours blended by non-periodic value noise and the central
// scene's under a 3-D noise brightness, which structure-from-motion can match (`from-photos` on it).
enum class UnboundedTexture { checker, noise };

struct UnboundedOptions {
  uint32_t width_px = 256;        // full-resolution images (images/), 4:3; images_<factor>/ are box-downsampled
  uint32_t views = 40;            // around the scene: two rings (heights 0.6 and 1.6), azimuths interleaved
  uint32_t factor = 4;            // also write images_<factor>/ (1: none)
  uint64_t seed = 0;              // azimuth jitter and sub-pixel jitter
  uint32_t samples_per_axis = 4;  // jittered supersampling per pixel
  unsigned threads = 0;           // 0: every hardware thread
  double camera_angle_x = 0.87;   // horizontal field of view, radians (50°)
  double camera_distance = 4.0;   // the orbit's radius (horizontal), around the scene's centre
  bool jpeg = false;              // JPEG (quality 95), else PNG
  UnboundedTexture texture = UnboundedTexture::checker;
};

// Checks sizes and counts; throws mipnerf::Error saying what to change.
void validate(const UnboundedOptions& options);
// What a ray sees: the procedural scene, else the nearest of the ground (z = −0.7, a 1-unit checker) and the
// pillars (8 striped boxes 6 to 40 from the centre), else the sky (a colour of the direction, t = +∞).
SceneHit trace_unbounded(const Ray& ray);
// The same scene with UnboundedTexture::noise surfaces (same geometry, same depths); unbounded_tracer picks one.
SceneHit trace_unbounded_noise(const Ray& ray);
SceneHit (*unbounded_tracer(UnboundedTexture texture))(const Ray&);
// The cameras, full resolution, OpenGL axes, in orbit order; near/far from the finite depths each sees (0.9× the
// nearest, 1.1× the 99th percentile of a 32×24 grid of rays).
std::vector<Camera> unbounded_cameras(const UnboundedOptions& options);
void write_unbounded_scene(const std::string& out_dir, const UnboundedOptions& options, const LogFn& log = {});

}  // namespace mipnerf::data
