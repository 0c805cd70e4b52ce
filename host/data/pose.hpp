// Camera poses: reading a camera-to-world matrix from JSON with validation (finite, rigid, right-handed),
// building look-at poses, and the point closest to all optical axes (where a capture looks).
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "core/vec3.hpp"
#include "io/json.hpp"

namespace mipnerf::data {

using Matrix34 = std::array<double, 12>;  // row-major 3×4, as Camera::camera_to_world

// Rotation tolerance of check_rigid_pose: max |RᵀR − I| and |det R − 1|. Poses exported as float32 (Blender's
// JSON) are orthonormal to ~1e-7; a scaled or sheared matrix is off by far more than 1e-3.
constexpr double kRigidTolerance = 1e-3;

// A 4×4 (or 3×4) camera-to-world matrix, given as an array of rows. Throws mipnerf::Error naming `where` when
// it has the wrong shape, a non-number or non-finite entry, a last row other than 0 0 0 1, or is not rigid.
Matrix34 pose_from_json(const io::Json& value, const std::string& where);
// The same matrix as a 4×4 JSON array (for writing transforms files).
io::Json pose_to_json(const Matrix34& camera_to_world);

// Throws unless every entry is finite and the rotation is orthonormal with determinant +1 (within
// kRigidTolerance); the message gives the deviation and what it likely means.
void check_rigid_pose(const Matrix34& camera_to_world, const std::string& where);

// ---- Rigid 3×4 poses (the one home of pose conventions: the LLFF loader, the COLMAP import and the camera paths
// all recentre, rescale and look at through these) ----

// Column c of the pose: 0..2 the camera's x, y, z axes in world, 3 its position.
inline Vec3 column(const Matrix34& m, int c) { return {m[c], m[4 + c], m[8 + c]}; }
Matrix34 from_columns(const Vec3& x, const Vec3& y, const Vec3& z, const Vec3& position);
// The official viewmatrix: a frame whose z is `z` normalised, x ⟂ (up, z), at `position`.
Matrix34 view_matrix(const Vec3& z, const Vec3& up, const Vec3& position);
// inverse(a) · b for a rigid `a` (orthonormal rotation): [Rᵀ | −Rᵀt] · b.
Matrix34 inverse_times(const Matrix34& a, const Matrix34& b);
// The official poses_avg: centre = mean position, z = normalised sum of z axes, up = sum of y axes.
Matrix34 average_pose(const std::vector<Matrix34>& poses);
// Every pose expressed in the frame of their average_pose (the official recenter_poses).
void recentre(std::vector<Matrix34>& poses);
// Positions scaled by s (rotations unchanged): a change of the world's unit.
void scale_positions(std::vector<Matrix34>& poses, double s);
// Positions mapped x → s·(x − centre) (rotations unchanged): the world's origin moved to `centre`, then rescaled.
void centre_and_scale(std::vector<Matrix34>& poses, const Vec3& centre, double s);

// LLFF's NDC world for any forward-facing capture (google/mipnerf datasets.py, LLFF: bd_factor 0.75, then
// recenter_poses): positions scaled by 1/(0.75·nearest_depth), so the nearest depth becomes 4/3 and NDC's near plane at
// depth 1 lies before the scene, then every pose expressed in the frame of their average pose (the cameras look down
// −z). Returns the scale (new units per old unit). Throws naming `where` when nearest_depth is not positive or there
// are no poses. The LLFF loader does the same steps inline (with its extent check between them).
double move_into_ndc_world(std::vector<Matrix34>& poses, double nearest_depth, const std::string& where);

// Whether the cameras look forward, as a forward-facing capture does (LLFF's, and its imgs2poses from a COLMAP
// model): every optical axis within 45° of their mean, so they spread over less than 90°. False for a capture that
// looks inward from all around (360°), and when the axes cancel out.
bool looks_forward(const std::vector<Matrix34>& camera_to_world);

// A camera at `eye` looking at `target` with world `up` roughly up in the image (OpenGL axes: −z forward).
Matrix34 look_at_pose(const Vec3& eye, const Vec3& target, const Vec3& up);

Vec3 camera_center(const Camera& camera);
// Unit direction the camera looks along (−z_camera in world).
Vec3 optical_axis(const Camera& camera);

// The least-squares point closest to every camera's optical axis (line through the centre along the axis):
// solves Σ (I − d dᵀ) p = Σ (I − d dᵀ) o. Empty when the axes are (nearly) parallel or there are none.
std::optional<Vec3> closest_point_to_axes(const std::vector<Camera>& cameras);

// The world an unbounded run's contraction expects of a capture taken all around (mip-NeRF 360: the scene's centre at
// the origin, the cameras about one unit out, everything beyond the ball of radius 1 contracted): the centre is the
// point closest to every optical axis (where the capture looks, as the official spherify takes it), else, with
// parallel axes, the mean camera position; the scale makes the cameras' root-mean-square distance from it 1, as
// spherify's does (data/formats/llff_capture.cpp). Applied with centre_and_scale; rotations are left as they are
// (the contraction is the same in every direction).
struct WorldAroundCameras {
  Vec3 centre{};
  double scale = 1.0;           // new units per old unit
  bool centre_is_look_at = true;  // false: the mean camera position (parallel axes)
};
// Throws mipnerf::Error naming `where` when there are no poses or every camera sits at the centre.
WorldAroundCameras world_around_cameras(const std::vector<Matrix34>& camera_to_world, const std::string& where);

}  // namespace mipnerf::data
