// `mipnerf-cl view`'s requests and responses, without sockets: the route table, the token check, the run folder's
// files, and the renders, so doctest tests and the fuzz target drive exactly what the HTTP server (view/http_server)
// serves. Every request gets a response; nothing a client sends makes it throw. The JSON of the API is read and
// written here (with view/api_json); the renderer behind it (view/render_backend.hpp) takes and returns types.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "view/render_backend.hpp"
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
