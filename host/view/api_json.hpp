// The viewer's HTTP API as JSON (docs/viewer.md), both ways: the page's cameras and output read into typed values,
// and the backend's typed state written as the page reads it. The request handler is its only user.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "view/render_backend.hpp"

namespace mipnerf::view {

// "rgb" | "depth" | "acc" → the output; false for anything else.
bool parse_render_output(const std::string& name, RenderOutput& out);

// The page's camera: a camera path of exactly one frame ({"frames": [{transform_matrix, fl_x, ...}]}), read as
// `render --path` reads a file, with what it leaves out from `defaults`. Throws mipnerf::Error naming what is wrong.
Camera page_camera(const nlohmann::json& camera_path, const data::CameraPathDefaults& defaults);
// A recorded path's keyframes, read alike (any number of frames). Throws mipnerf::Error.
std::vector<Camera> recorded_keyframes(const nlohmann::json& camera_path, const data::CameraPathDefaults& defaults);

nlohmann::json to_json(const PathStatus& status);
nlohmann::json to_json(const RenderProgress& progress);
nlohmann::json to_json(const ViewerStatus& status);
nlohmann::json to_json(const StartCameras& cameras);

}  // namespace mipnerf::view
