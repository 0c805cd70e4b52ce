// Shared helpers for every mipnerf-cl program; prepended before a stage's own file.
// Plain OpenCL C 1.2. Conventions used by all kernels:
//  - 1-D launches are padded to a multiple of the work-group size (host/cl/launch.hpp), so every
//    kernel starts with `if (i >= n) return;` and none uses a barrier after that guard.
//  - Arrays are flat, row-major, float32; a 3-vector is 3 consecutive floats (never float3, whose
//    16-byte alignment would change the layout).

#ifndef MIPNERF_COMMON_CL
#define MIPNERF_COMMON_CL

// Loads/stores a packed 3-vector at element index i (i.e. floats 3i..3i+2).
inline float3 load3(__global const float* p, size_t i) { return (float3)(p[3 * i], p[3 * i + 1], p[3 * i + 2]); }
inline void store3(__global float* p, size_t i, float3 v) {
  p[3 * i] = v.x;
  p[3 * i + 1] = v.y;
  p[3 * i + 2] = v.z;
}

// Packed camera layout, [C][CAMERA_STRIDE] floats; mirrors host/data/camera.hpp (camera_layout).
#define CAMERA_TO_WORLD 0 /* 12 floats, 3x4 row-major, OpenGL axes (camera looks down -z) */
#define CAMERA_FOCAL_X 12 /* pixels */
#define CAMERA_FOCAL_Y 13
#define CAMERA_CENTER_X 14 /* principal point, pixels from the left edge */
#define CAMERA_CENTER_Y 15 /* pixels from the top edge */
#define CAMERA_WIDTH 16
#define CAMERA_HEIGHT 17
#define CAMERA_NEAR 18
#define CAMERA_FAR 19
#define CAMERA_LOSSMULT 20
#define CAMERA_STRIDE 24

#endif
