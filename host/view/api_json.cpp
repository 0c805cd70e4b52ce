// The viewer's HTTP API as JSON: reading the page's cameras, writing the renderer's state.
#include "view/api_json.hpp"

#include "core/error.hpp"
#include "data/paths/camera_path.hpp"

namespace mipnerf::view {
namespace {

const char* state_name(PathStatus::State state) {
  switch (state) {
    case PathStatus::State::idle: return "idle";
    case PathStatus::State::rendering: return "rendering";
    case PathStatus::State::done: return "done";
    case PathStatus::State::failed: return "failed";
    case PathStatus::State::cancelled: return "cancelled";
  }
  return "failed";
}

nlohmann::json frames_json(const std::vector<Camera>& cameras) {
  nlohmann::json out = nlohmann::json::array();
  for (const Camera& c : cameras) out.push_back(data::camera_frame_json(c));
  return out;
}

}  // namespace

bool parse_render_output(const std::string& name, RenderOutput& out) {
  if (name == "rgb") out = RenderOutput::rgb;
  else if (name == "depth") out = RenderOutput::depth;
  else if (name == "acc") out = RenderOutput::acc;
  else return false;
  return true;
}

Camera page_camera(const nlohmann::json& camera_path, const data::CameraPathDefaults& defaults) {
  const std::vector<Camera> cameras = data::camera_path_from_json(camera_path, "the page's camera", defaults);
  if (cameras.size() != 1) throw Error("the page's camera: give exactly one frame");
  return cameras.front();
}

std::vector<Camera> recorded_keyframes(const nlohmann::json& camera_path, const data::CameraPathDefaults& defaults) {
  return data::camera_path_from_json(camera_path, "the viewer's recorded path", defaults);
}

nlohmann::json to_json(const PathStatus& p) {
  return {{"state", state_name(p.state)}, {"frames_done", p.frames_done}, {"frames", p.frames},
          {"seconds", p.seconds},         {"eta_seconds", p.eta_seconds}, {"folder", p.folder},
          {"video", p.video},             {"first_frame", p.first_frame}, {"message", p.message}};
}

nlohmann::json to_json(const RenderProgress& p) {
  return {{"rendering", p.rendering},   {"generation", p.generation}, {"divisor", p.divisor},
          {"done_rays", p.done_rays},   {"total_rays", p.total_rays}, {"seconds", p.seconds}};
}

nlohmann::json to_json(const ViewerStatus& s) {
  return {{"device", s.device},
          {"step", s.step},
          {"checkpoint", s.checkpoint},
          {"chunk_rays", s.chunk_rays},
          {"warm_up_seconds", s.warm_up_seconds}};
}

nlohmann::json to_json(const StartCameras& cameras) {
  nlohmann::json out;
  out["train"] = frames_json(cameras.train);
  out["spiral"] = frames_json(cameras.spiral);
  if (cameras.start == StartCameras::View::train) {
    out["start"] = {{"view", "train"}, {"index", 0}, {"why", cameras.why}};
  } else {
    out["start"] = {{"view", "orbit"}, {"why", cameras.why}};
  }
  out["orbit"] = {{"target", cameras.orbit.target},
                  {"up", cameras.orbit.up},
                  {"radius", cameras.orbit.radius},
                  {"elevation_deg", cameras.orbit.elevation_deg},
                  {"frame", data::camera_frame_json(cameras.orbit.frame)}};
  return out;
}

}  // namespace mipnerf::view
