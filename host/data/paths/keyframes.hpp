// A camera path from a few keyframes: the cameras in between, for a smooth video of a path recorded in the viewer
// (`mipnerf-cl view`) or written by hand (`render --path FILE --frames N`).
#pragma once

#include <cstdint>
#include <vector>

#include "core/camera.hpp"

namespace mipnerf::data {

// `frames` cameras along the keyframes, evenly spaced in the keyframe parameter: frame 0 is the first keyframe, the
// last frame the last keyframe, and with frames = 1 + m·(K − 1) every m-th frame is a keyframe exactly.
// - Positions follow a Catmull–Rom spline through the camera centres (the end segments mirror their neighbour), so
//   the path passes through every keyframe with a continuous velocity; with two keyframes it is the straight line.
// - Orientations are slerped between consecutive keyframes (unit quaternions, shortest arc), so every frame's
//   rotation stays orthonormal and turns at a constant rate within a segment.
// - Focal lengths, principal point, near and far are interpolated linearly; lossmult is the first keyframe's.
// Throws mipnerf::Error for no keyframes, frames = 0, keyframes of differing image sizes or with a lens (the page and
// path files give pinholes), or frames < keyframes (the path would skip keyframes). One keyframe gives `frames`
// copies of it.
std::vector<Camera> interpolate_keyframes(const std::vector<Camera>& keyframes, uint32_t frames);

// The rotation part of a camera-to-world pose as a unit quaternion (w, x, y, z) with w ≥ 0, and back.
std::array<double, 4> rotation_to_quaternion(const std::array<double, 12>& camera_to_world);
std::array<double, 9> quaternion_to_rotation(const std::array<double, 4>& q);

}  // namespace mipnerf::data
