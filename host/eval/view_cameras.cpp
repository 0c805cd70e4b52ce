// Split, orbit and camera-path cameras for rendering a checkpoint.
#include "eval/view_cameras.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/error.hpp"
#include "data/formats/formats.hpp"
#include "data/paths/keyframes.hpp"
#include "eval/evaluate.hpp"
#include "eval/image_output.hpp"
#include "eval/render_setup.hpp"
#include "train/model.hpp"

namespace mipnerf::eval {
namespace fs = std::filesystem;
namespace {

// Nothing to fit an orbit to: Blender's camera, 400x400, with the model's near/far or Blender's.
Camera default_orbit_intrinsics(const train::TrainConfig& config) {
  Camera c;
  c.width_px = c.height_px = 400;
  c.focal_x_px = c.focal_y_px = 0.5 * c.width_px / std::tan(0.5 * data::kDefaultCameraAngleX);
  c.center_x_px = c.center_y_px = 200.0;
  c.near = config.near > 0 ? config.near : 2.0;
  c.far = config.far > 0 ? config.far : 6.0;
  return c;
}

nlohmann::ordered_json orbit_details(const data::OrbitOptions& orbit, bool fitted) {
  return {{"kind", "orbit"},
          {"fitted_to_training_cameras", fitted},
          {"target", orbit.target},
          {"up", orbit.up},
          {"radius", orbit.radius},
          {"elevation_deg", orbit.elevation_deg},
          {"start_azimuth_deg", orbit.start_azimuth_deg},
          {"frames", orbit.frames}};
}

}  // namespace

std::string frame_stem(size_t index) {
  char text[32];
  std::snprintf(text, sizeof(text), "frame_%04zu", index);
  return text;
}

ViewFrames split_views(const train::TrainedModel& model, const std::string& checkpoint, const SplitViewRequest& request,
                       const data::ResolutionRequest& resolution) {
  const std::string& name = request.split;
  const std::string data_path = resolve_data_path(request.data, model, checkpoint);
  const data::Dataset dataset =
      data::load_dataset(data_path, train::load_options(model.config, data_path, {name}, request.scales));
  const data::Split& split = dataset.split(name);
  ViewFrames frames;
  frames.source = "the " + name + " split of " + data_path;
  frames.default_folder = "render_" + name;
  const std::vector<std::string> stems = split_image_stems(split);
  for (size_t i : select_views(split, request.views)) {
    frames.cameras.push_back(data::resize_camera(split.cameras[i], resolution));
    frames.stems.push_back(stems[i]);
  }
  frames.details = {{"kind", "split"}, {"data", data_path}, {"split", name}};
  return frames;
}

std::vector<Camera> training_cameras(const train::TrainedModel& model, const std::string& data) {
  std::string path = data;
  std::error_code ec;
  if (path.empty() && !model.data_path.empty() && fs::exists(model.data_path, ec)) path = model.data_path;
  if (path.empty()) return {};
  const data::Dataset dataset = data::load_dataset(path, train::load_options(model.config, path, {"train"}, 1));
  const data::Split& train = dataset.split("train");
  std::vector<Camera> cameras;
  for (size_t i = 0; i < train.num_images(); ++i) {
    if (train.scale_levels[i] == 0) cameras.push_back(train.cameras[i]);
  }
  return cameras;
}

ViewFrames orbit_views(const train::TrainedModel& model, const OrbitRequest& request,
                       const data::ResolutionRequest& resolution) {
  const auto cameras = training_cameras(model, request.data);
  data::OrbitOptions orbit;
  if (!cameras.empty()) {
    orbit = data::orbit_around(cameras);
  } else {
    orbit.intrinsics = default_orbit_intrinsics(model.config);
  }
  if (request.radius) orbit.radius = *request.radius;
  orbit.elevation_deg = request.elevation_deg;
  orbit.start_azimuth_deg = request.start_azimuth_deg;
  orbit.frames = request.frames;
  orbit.intrinsics = data::resize_camera(orbit.intrinsics, resolution);
  Camera& c = orbit.intrinsics;
  if (request.fov_deg) c.focal_x_px = c.focal_y_px = 0.5 * c.width_px / std::tan(0.5 * *request.fov_deg * M_PI / 180.0);
  if (request.focal_px) c.focal_x_px = c.focal_y_px = *request.focal_px;
  ViewFrames frames;
  frames.source = "an orbit";
  frames.default_folder = "render_orbit";
  frames.cameras = data::orbit_cameras(orbit);
  for (size_t i = 0; i < frames.cameras.size(); ++i) frames.stems.push_back(frame_stem(i));
  frames.details = orbit_details(orbit, !cameras.empty());
  return frames;
}

ViewFrames spiral_views(const train::TrainedModel& model, const std::string& checkpoint, const std::string& data,
                        uint32_t frames, const data::ResolutionRequest& resolution) {
  const std::string data_path = resolve_data_path(data, model, checkpoint);
  const data::FormatReader& reader = data::detect_reader(data_path);
  if (reader.render_path == nullptr) {
    throw Error(data_path + ": --path spiral follows an LLFF capture's cameras (poses_bounds.npy), or a forward-facing "
                "transforms.json trained in NDC; this is a " + reader.name + " dataset: use --path orbit");
  }
  const data::LoadOptions options = train::load_options(model.config, data_path, {"train"}, 1);
  const data::FormatRenderPath path = reader.render_path(data_path, options, static_cast<int>(frames));
  ViewFrames views;
  views.source = path.description;
  views.default_folder = "render_spiral";
  for (const Camera& camera : path.cameras) {
    views.cameras.push_back(data::resize_camera(camera, resolution));
    views.stems.push_back(frame_stem(views.stems.size()));
  }
  views.details = {{"kind", path.kind}, {"data", data_path}, {"frames", frames}};
  return views;
}

data::CameraPathDefaults camera_path_defaults(const train::TrainedModel& model,
                                              const data::ResolutionRequest& resolution) {
  data::CameraPathDefaults defaults;
  // Without w/h in the file, an explicit size is the frames' size.
  if (resolution.scale <= 0.0 && resolution.width && resolution.height) {
    defaults.width = resolution.width;
    defaults.height = resolution.height;
  }
  // near/far: the run's settings when it has them; else NDC's 0..1 for a run of cylinders (the ray kernel's cylinders
  // are NDC rays: a forward-facing capture, whose dataset cameras say 0..1 too); else the training cameras' own (a
  // capture's bounds), when the data is still there; else Blender's 2..6. Blender's range on an NDC run sampled
  // beyond the far plane: the viewer's free camera on a forward-facing run rendered 2 dB below the same camera's
  // `render --split train` (15.1 against 17.1 dB from its photo, a short tiny run).
  if (model.config.ray_shape == RayShape::cylinder) {
    defaults.near = 0.0;
    defaults.far = 1.0;
  } else if (model.config.unbounded) {  // sampled from the camera out, as it trained (train::load_options)
    defaults.near = train::kUnboundedNear;
    defaults.far = train::kUnboundedFar;
  } else if (!(model.config.near > 0 && model.config.far > 0)) {
    const std::vector<Camera> train = training_cameras(model, "");
    if (!train.empty()) {
      defaults.near = train.front().near;
      defaults.far = train.front().far;
    }
  }
  if (model.config.near > 0) defaults.near = model.config.near;
  if (model.config.far > 0) defaults.far = model.config.far;
  return defaults;
}

namespace {

ViewFrames frames_along(const std::vector<Camera>& file_cameras, const data::ResolutionRequest& resolution,
                        uint32_t interpolated_frames) {
  const std::vector<Camera> cameras =
      interpolated_frames > 0 ? data::interpolate_keyframes(file_cameras, interpolated_frames) : file_cameras;
  ViewFrames frames;
  for (const auto& camera : cameras) {
    frames.cameras.push_back(data::resize_camera(camera, resolution));
    frames.stems.push_back(frame_stem(frames.stems.size()));
  }
  return frames;
}

}  // namespace

ViewFrames path_views(const train::TrainedModel& model, const std::string& path_file,
                      const data::ResolutionRequest& resolution, uint32_t interpolated_frames) {
  const data::CameraPathDefaults defaults = camera_path_defaults(model, resolution);
  const std::vector<Camera> file_cameras = data::read_camera_path(path_file, defaults);
  ViewFrames frames = frames_along(file_cameras, resolution, interpolated_frames);
  frames.source = "the camera path " + path_file;
  frames.default_folder = "render_" + fs::path(path_file).stem().string();
  frames.details = {{"kind", "path"}, {"file", fs::absolute(path_file).lexically_normal().string()}};
  if (interpolated_frames > 0) frames.details["keyframes"] = file_cameras.size();
  return frames;
}

ViewFrames path_views(const std::vector<Camera>& keyframes, const std::string& source,
                      const data::ResolutionRequest& resolution, uint32_t interpolated_frames) {
  ViewFrames frames = frames_along(keyframes, resolution, interpolated_frames);
  frames.source = source;
  frames.default_folder = "render_path";
  frames.details = {{"kind", "path"}, {"source", source}};
  if (interpolated_frames > 0) frames.details["keyframes"] = keyframes.size();
  return frames;
}

void apply_depth_range(std::vector<Camera>& cameras, std::optional<double> near, std::optional<double> far) {
  for (auto& camera : cameras) {
    if (near) camera.near = *near;
    if (far) camera.far = *far;
    if (!(camera.far > camera.near)) {
      throw Error("near " + std::to_string(camera.near) + " is not below far " + std::to_string(camera.far) +
                  ": fix --near/--far");
    }
  }
}

}  // namespace mipnerf::eval
