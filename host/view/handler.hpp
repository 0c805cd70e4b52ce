// `mipnerf-cl view`'s requests and responses, without sockets: the route table, the token check, the run folder's
// files, and the renders, so doctest tests and the fuzz target drive exactly what the HTTP server (view/http_server)
// serves. Every request gets a response; nothing a client sends makes it throw.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "view/request_guard.hpp"

namespace mipnerf::view {

// What the HTTP server passes in: the method, the request target as the client sent it (path and query, still
// percent-encoded: the handler decodes it, once), the body, and the headers the handler checks (empty when absent;
// a header sent twice arrives empty, so it fails the checks that need it).
struct Request {
  std::string method;  // "GET", "POST", ...
  std::string target;  // "/run/val/000_scale0.png?token=..."
  std::string body;
  std::string host;            // Host: "127.0.0.1:8000"
  std::string origin;          // Origin: "http://127.0.0.1:8000", or empty
  std::string content_type;    // Content-Type: "application/json"
  std::string sec_fetch_site;  // Sec-Fetch-Site: "same-origin", "cross-site", … (browsers send it), or empty
};

struct Response {
  int status = 200;
  std::string content_type = "text/plain; charset=utf-8";
  std::string body;
  std::vector<std::pair<std::string, std::string>> headers;  // beside Content-Type and Content-Length
};

// One image the page asked for, already checked: the camera as a transforms-style camera path text (one frame), the
// divisor of its size (8, 4, 2 or 1), what to draw, and the page's request counter (newest wins).
struct RenderRequest {
  std::string camera_json;  // {"frames": [{transform_matrix, fl_x, fl_y, cx, cy, w, h}]}
  int divisor = 1;
  std::string output = "rgb";  // rgb | depth | acc
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
  std::string keyframes_json;  // {"frames": [{transform_matrix, fl_x, fl_y, cx, cy, w, h}, ...]}
  uint32_t frames = 60;
  int divisor = 1;
  double fps = 30.0;
};

struct PathReply {
  enum class Status { started, busy, bad_request };
  Status status = Status::started;
  std::string message;  // why, when not started
};

// What renders the page's cameras: a trained model on a device (view/view_renderer), or a test double.
class RenderBackend {
 public:
  virtual ~RenderBackend() = default;
  virtual RenderReply render(const RenderRequest& request) = 0;
  // Starts rendering a recorded path in the background (one at a time) and returns at once.
  virtual PathReply start_path(const PathRequest& request) = 0;
  // The path render's progress, as JSON text: {"state": "idle" | "rendering" | "done" | "failed" | "cancelled",
  // "frames_done", "frames", "seconds", "eta_seconds", "folder" (run-relative), "video" (run-relative, "" without
  // one), "first_frame" (run-relative), "message"}.
  virtual std::string path_status_json() = 0;
  // Asks a running path render to stop after its current chunk of rays (its partial video is not kept).
  virtual void cancel_path() = 0;
  // The cameras to start from, as JSON text: {"train": [frames], "orbit": {...}} (see view_renderer.hpp).
  virtual std::string cameras_json() = 0;
  // The device and the checkpoint it renders, as JSON text.
  virtual std::string status_json() = 0;
  // The render under way (a full-size frame on a CPU takes tens of seconds), as JSON text: {"rendering": bool,
  // "generation", "divisor", "done_rays", "total_rays", "seconds"}; the last one's when none is.
  virtual std::string render_progress_json() = 0;
};

struct HandlerOptions {
  std::string run_folder;       // the run: every file served under /run/ lies inside it
  std::string token;            // when not empty, every request must carry ?token=<this>
  BoundAddress bound;           // every request's Host must name it (view/request_guard.hpp); its port may be set
                                // once the server has bound (Handler::set_port)
  size_t max_body_bytes = 1 << 16;   // a render request's camera is < 1 KB
  size_t max_target_bytes = 4096;    // path and query
  size_t max_file_bytes = 64 << 20;  // a run folder's image or log
};

class Handler {
 public:
  // `backend` may be null: then render and camera requests answer 503 (the tests of everything else need no device;
  // `view` serves the run before its first checkpoint exists and sets the backend once one loads).
  Handler(HandlerOptions options, RenderBackend* backend);
  void set_backend(RenderBackend* backend) { backend_.store(backend); }
  // The port the server bound (with --port 0 known only after binding); before it is set, options().bound.port.
  void set_port(int port) { port_.store(port); }
  // Every request: 403 unless its Host names the bound address (request_guard.hpp) and it carries the token when
  // one is set; a request that changes state (any method but GET and HEAD) also 403 when it comes from another
  // origin (Origin, Sec-Fetch-Site) and 415 unless its body is declared JSON.
  Response handle(const Request& request) const;
  const HandlerOptions& options() const { return options_; }

 private:
  Response answer(const Request& request) const;  // handle, without the headers every response carries
  Response route(const std::string& method, const std::string& path, const Request& request) const;
  Response serve_run_file(const std::string& relative) const;
  Response render(const std::string& body) const;
  Response start_path(const std::string& body) const;
  // The Host, Origin and Content-Type checks; a response to send instead of routing, or status 0 when all pass.
  Response refuse_foreign(const Request& request) const;

  HandlerOptions options_;
  std::atomic<int> port_;
  std::string run_root_;  // canonical run folder
  std::atomic<RenderBackend*> backend_;
};

// Percent-decodes `text` ('+' stays '+'); false for a malformed escape or a decoded NUL byte.
bool percent_decode(const std::string& text, std::string& out);

// The value of `key` in a query string ("a=1&token=x"), percent-decoded; empty when absent or malformed.
std::string query_value(const std::string& query, const std::string& key);

// The file `relative` (decoded, '/'-separated) names inside `root` (a canonical folder), or empty when it names
// nothing inside it: an absolute path, a `..` component, a NUL, or a path whose symlinks resolve outside `root`.
std::string resolve_inside(const std::string& root, const std::string& relative);

// Compares two strings in time independent of where they differ (the token).
bool same_secret(const std::string& a, const std::string& b);

}  // namespace mipnerf::view
