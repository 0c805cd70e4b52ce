// What renders the viewer's cameras, as typed values: the page's camera as a `Camera`, what to draw as an enum, and
// the renderer's state as structs. Only the request handler (view/handler.cpp, view/api_json.cpp) reads and writes
// the JSON of docs/viewer.md; a backend (view/view_renderer, or a test double) never sees it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "core/vec3.hpp"
#include "data/paths/camera_path.hpp"

namespace mipnerf::view {

// What a render draws: the colour, or the last level's expected depth or accumulated opacity as grey levels.
enum class RenderOutput { rgb, depth, acc };

// One image the page asked for, already checked: its camera (as the page sent it, before the divisor), the divisor
// of its size (8, 4, 2 or 1), what to draw, and the page's request counter (newest wins).
struct RenderRequest {
  Camera camera;
  int divisor = 1;
  RenderOutput output = RenderOutput::rgb;
  uint64_t generation = 0;
};

struct RenderReply {
  enum class Status { ok, superseded, busy, bad_request, failed };
  Status status = Status::ok;
  std::string png;  // the image, 8-bit PNG
  uint32_t width = 0, height = 0;
  double seconds = 0.0;  // render wall time
  int64_t step = 0;      // the checkpoint's step
  std::string message;   // why, when not ok
};

// A path recorded in the page, to render into the run folder as frames and a video (as `render --path FILE
// --frames N --video` would): its keyframes, the frames along them, the divisor of the keyframes' size, the video's
// frame rate.
struct PathRequest {
  std::vector<Camera> keyframes;
  uint32_t frames = 60;
  int divisor = 1;
  double fps = 30.0;
};

struct PathReply {
  enum class Status { started, busy, bad_request };
  Status status = Status::started;
  std::string message;  // why, when not started
};

// A path render's progress (GET /api/path).
struct PathStatus {
  enum class State { idle, rendering, done, failed, cancelled };
  State state = State::idle;
  size_t frames_done = 0, frames = 0;
  double seconds = 0.0, eta_seconds = 0.0;
  std::string folder;       // run-relative: view_paths/path_<UTC time>
  std::string video;        // run-relative, empty without one
  std::string first_frame;  // run-relative
  std::string message;      // why it failed or was cancelled
};

// The free camera's render under way, or the last one when none is (GET /api/render/progress).
struct RenderProgress {
  bool rendering = false;
  uint64_t generation = 0;
  int divisor = 0;
  size_t done_rays = 0, total_rays = 0;
  double seconds = 0.0;  // so far, or the last render's whole time
};

// The device and the checkpoint it renders (GET /api/run's "viewer").
struct ViewerStatus {
  std::string device;
  int64_t step = 0;
  std::string checkpoint;  // its file name
  size_t chunk_rays = 0;
  double warm_up_seconds = 0.0;
};

// The cameras the page's camera can start from, and the one it starts from (GET /api/cameras).
struct StartCameras {
  std::vector<Camera> train;   // the training split's cameras (empty when the training data is gone)
  std::vector<Camera> spiral;  // a forward-facing capture's official render path (empty for other data)
  struct Orbit {
    Vec3 target{0.0, 0.0, 0.0}, up{0.0, 0.0, 1.0};
    double radius = 0.0, elevation_deg = 0.0;
    Camera frame;  // the orbit's first camera
  } orbit;
  enum class View { train, orbit };
  View start = View::orbit;  // a forward-facing capture starts from train[0]
  std::string why;           // why that one, for the page
};

class RenderBackend {
 public:
  virtual ~RenderBackend() = default;
  // What the page's cameras may leave out (near/far: the run's), as the handler reads them.
  virtual data::CameraPathDefaults camera_defaults() = 0;
  virtual RenderReply render(const RenderRequest& request) = 0;
  // Starts rendering a recorded path in the background (one at a time) and returns at once.
  virtual PathReply start_path(const PathRequest& request) = 0;
  virtual PathStatus path_status() = 0;
  // Asks a running path render to stop after its current chunk of rays (its partial video is not kept).
  virtual void cancel_path() = 0;
  virtual StartCameras start_cameras() = 0;
  virtual ViewerStatus status() = 0;
  // The render under way (a full-size frame on a CPU takes tens of seconds), or the last one when none is.
  virtual RenderProgress render_progress() = 0;
};

}  // namespace mipnerf::view
