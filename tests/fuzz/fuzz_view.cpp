// Fuzz target: `mipnerf-cl view`'s request handler (view::Handler), the part of the viewer that reads what a browser,
// or anyone who can reach the port, sends. The input is one request: its first byte chooses the method (G: GET, P:
// POST, H: HEAD, else PUT), the bytes up to the first newline are the target (path and query, percent-encoded), then
// any lines that start "Host:", "Origin:", "Content-Type:" or "Sec-Fetch-Site:" are those headers (without a Host line
// the page's own, 127.0.0.1:8000, and without a Content-Type line application/json), and the rest is the body. The
// run folder holds a log, a config and an image, and a symlink to a file outside it. Every request must get a status
// in 200..599; no response may contain the outside file's text; only a request whose Host names the viewer may get a
// 2xx, and a state-changing one only from its own origin with a JSON body; a render request's camera is read by the
// handler with the camera path reader (data::camera_path_from_json), whose errors must be mipnerf::Error (a 400), and
// a camera it passes on must have pixels.
#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.hpp"
#include "data/paths/camera_path.hpp"
#include "data/paths/keyframes.hpp"
#include "fuzz_support.hpp"
#include "view/handler.hpp"
#include "view/request_guard.hpp"

namespace {

namespace fs = std::filesystem;
using namespace mipnerf;

constexpr const char* kSecret = "FUZZ-SECRET-OUTSIDE-THE-RUN";

struct CameraReadingBackend : view::RenderBackend {
  data::CameraPathDefaults camera_defaults() override { return {}; }
  view::RenderReply render(const view::RenderRequest& request) override {
    view::RenderReply reply;
    fuzz::check(request.camera.width_px > 0 && request.camera.height_px > 0, "a camera without pixels was accepted");
    reply.png = "image";
    return reply;
  }
  view::StartCameras start_cameras() override { return {}; }
  view::ViewerStatus status() override { return {}; }
  view::RenderProgress render_progress() override { return {}; }
  // A path's keyframes go through the interpolation the real renderer uses (frames capped: the handler allows 3600,
  // the fuzzer need not build them all).
  view::PathReply start_path(const view::PathRequest& request) override {
    view::PathReply reply;
    try {
      const auto frames = data::interpolate_keyframes(request.keyframes, std::min<uint32_t>(request.frames, 64));
      fuzz::check(!frames.empty(), "a path without frames was accepted");
    } catch (const Error&) {
      reply.status = view::PathReply::Status::bad_request;
    }
    return reply;
  }
  view::PathStatus path_status() override { return {}; }
  void cancel_path() override {}
};

const fs::path& run_folder() {
  static const fs::path run = [] {
    const fs::path scratch = fuzz::scratch_folder();
    const fs::path dir = scratch / "view_run";
    fs::create_directories(dir / "val");
    std::ofstream(scratch / "secret.txt") << kSecret;
    std::ofstream(dir / "config.json") << R"({"steps": 10})";
    std::ofstream(dir / "train_log.csv") << "step,wall_seconds,loss,psnr\n2,0.5,0.3,9.5\n";
    std::ofstream(dir / "val" / "000_scale0.png") << "PNG";
    std::error_code ec;
    fs::create_symlink(scratch / "secret.txt", dir / "out.txt", ec);
    return dir;
  }();
  return run;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static CameraReadingBackend backend;
  static const view::BoundAddress bound{"127.0.0.1", 8000};
  static const view::Handler handler = [] {
    view::HandlerOptions options;
    options.run_folder = run_folder().string();
    options.bound = bound;
    return view::Handler(options, &backend);
  }();
  static const view::Handler with_token = [] {
    view::HandlerOptions options;
    options.run_folder = run_folder().string();
    options.token = "abc123";
    options.bound = bound;
    return view::Handler(options, &backend);
  }();
  const std::string input(reinterpret_cast<const char*>(data), size);
  view::Request request;
  const char first = size == 0 ? 'G' : input[0];
  request.method = first == 'G' ? "GET" : first == 'P' ? "POST" : first == 'H' ? "HEAD" : "PUT";
  std::string rest = size == 0 ? "" : input.substr(1);
  size_t newline = rest.find('\n');
  request.target = rest.substr(0, newline);
  rest = newline == std::string::npos ? "" : rest.substr(newline + 1);
  request.host = "127.0.0.1:8000";
  request.content_type = "application/json";
  const std::pair<const char*, std::string view::Request::*> headers[] = {{"Host:", &view::Request::host},
                                                                          {"Origin:", &view::Request::origin},
                                                                          {"Content-Type:", &view::Request::content_type},
                                                                          {"Sec-Fetch-Site:", &view::Request::sec_fetch_site}};
  for (bool more = true; more;) {
    more = false;
    for (const auto& [name, field] : headers) {
      if (rest.rfind(name, 0) != 0) continue;
      newline = rest.find('\n');
      request.*field = rest.substr(std::strlen(name), newline == std::string::npos ? std::string::npos
                                                                                     : newline - std::strlen(name));
      rest = newline == std::string::npos ? "" : rest.substr(newline + 1);
      more = true;
    }
  }
  request.body = rest;
  const bool changes_state = request.method != "GET" && request.method != "HEAD";
  for (const view::Handler* h : {&handler, &with_token}) {
    const view::Response response = h->handle(request);
    fuzz::check(response.status >= 200 && response.status < 600, "a response without a valid status");
    const bool served = response.status < 300;
    fuzz::check(!served || view::host_allowed(request.host, bound), "a request for another Host was served");
    fuzz::check(!served || !changes_state ||
                    (view::origin_allowed(request.origin, bound) && view::is_json_content_type(request.content_type)),
                "a state-changing request from another origin, or not JSON, was served");
    // (A 404 names the path it was asked for: the text may come back only when the request held it.)
    fuzz::check(response.body.find(kSecret) == std::string::npos || input.find(kSecret) != std::string::npos,
                "a file outside the run folder was served");
    fuzz::check(h == &handler || response.status >= 400 || request.target.find("abc123") != std::string::npos,
                "a request without the token was answered");
  }
  return 0;
}
