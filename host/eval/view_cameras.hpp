// The cameras `mipnerf-cl render` draws from a checkpoint: a dataset split's, an orbit around the training
// cameras, or a camera path file, each resized to the requested resolution and named for its output file.
#pragma once

#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "data/paths/camera_path.hpp"
#include "train/checkpoint.hpp"

namespace mipnerf::eval {

// What the frames are, with their cameras and output names.
struct ViewFrames {
  std::string source;          // for messages: "the test split of DIR", "an orbit", "the camera path FILE"
  std::string default_folder;  // under the run folder: render_<split>, render_orbit, render_<path file stem>
  std::vector<Camera> cameras;
  std::vector<std::string> stems;                                     // one output name (no extension) per camera
  nlohmann::ordered_json details = nlohmann::ordered_json::object();  // render.json's "source"
};

struct SplitViewRequest {
  std::string data;  // dataset folder; empty: the one the checkpoint was trained on
  std::string split = "test";
  size_t views = 0;  // 0: every view; n: the first n full-resolution views (all their scales)
  int scales = 0;    // > 0: build the multiscale pyramid with this many scales (else as trained)
};

// The split's cameras, named by split_image_stems. `checkpoint` names the file in errors about its data.
ViewFrames split_views(const train::TrainedModel& model, const std::string& checkpoint, const SplitViewRequest& request,
                       const data::ResolutionRequest& resolution);

struct OrbitRequest {
  std::string data;              // dataset the orbit is fitted to; empty: the checkpoint's, when it still exists
  std::optional<double> radius;  // scene units; default: fitted to the training cameras
  double elevation_deg = 30.0;
  double start_azimuth_deg = 0.0;
  uint32_t frames = 120;
  std::optional<double> fov_deg;   // horizontal field of view; default: the training camera's
  std::optional<double> focal_px;  // focal length in pixels of the output size
};

// An orbit fitted to the training cameras (data::orbit_around), or without them Blender's 400x400 camera at the
// default radius around the origin; frames named frame_0000, frame_0001, ...
ViewFrames orbit_views(const train::TrainedModel& model, const OrbitRequest& request,
                       const data::ResolutionRequest& resolution);

// The official render path of an LLFF capture (data::llff_render_path: the spiral, or the circle of a spherified
// one), `frames` views at the trained image size (resized as requested); frames named frame_0000, ... `checkpoint`
// names the file in errors about its data; the data must be an LLFF folder.
ViewFrames spiral_views(const train::TrainedModel& model, const std::string& checkpoint, const std::string& data,
                        uint32_t frames, const data::ResolutionRequest& resolution);

// What a camera path may leave out, for this model: its near/far (the run's settings, else NDC's 0..1 for a run of
// cylinders, else the training cameras' own when the data is still there (it is loaded for them), else 2..6), and the
// requested size when the path gives none (path_views and `mipnerf-cl view`'s cameras, so both render a page's camera
// alike).
data::CameraPathDefaults camera_path_defaults(const train::TrainedModel& model,
                                              const data::ResolutionRequest& resolution);

// The cameras of a transforms-style camera path file (data::read_camera_path), near/far defaulting to the model's.
// With interpolated_frames > 0 the file's frames are keyframes and the path is that many frames along them
// (data::interpolate_keyframes): a few recorded views become a smooth video.
ViewFrames path_views(const train::TrainedModel& model, const std::string& path_file,
                      const data::ResolutionRequest& resolution, uint32_t interpolated_frames = 0);
// The same from keyframes already read (the viewer's recorded path, which its request handler reads with
// camera_path_defaults); `source` names them in errors and records.
ViewFrames path_views(const std::vector<Camera>& keyframes, const std::string& source,
                      const data::ResolutionRequest& resolution, uint32_t interpolated_frames);

// The full-resolution training cameras of `data`, else of the checkpoint's data when it still exists; empty when
// neither is there.
std::vector<Camera> training_cameras(const train::TrainedModel& model, const std::string& data);

// Sets every camera's near and/or far bound where given. Throws mipnerf::Error when a camera's far is then not
// beyond its near, saying to fix --near/--far.
void apply_depth_range(std::vector<Camera>& cameras, std::optional<double> near, std::optional<double> far);

// "frame_0007": the output name of frame 7 of an orbit or path.
std::string frame_stem(size_t index);

}  // namespace mipnerf::eval
