// The viewer's route table: the page, the run's state, its files, and renders.
#include "view/handler.hpp"

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "view/api_json.hpp"
#include "view/page.hpp"
#include "view/run_state.hpp"

namespace mipnerf::view {
namespace fs = std::filesystem;
namespace {

Response text(int status, const std::string& message) {
  Response r;
  r.status = status;
  r.body = message + "\n";
  return r;
}

// What refuse_foreign returns when a request may go on to its route.
Response not_refused() {
  Response r;
  r.status = 0;
  return r;
}

// Renders and paths before the run's first checkpoint has loaded.
Response no_checkpoint_yet() {
  return text(503, "no checkpoint has loaded yet: the viewer renders once the run writes one");
}

// The object at `key` of a request (a camera path), or null when it is not one.
const nlohmann::json* object_at(const nlohmann::json& j, const char* key) {
  const auto it = j.find(key);
  return it == j.end() || !it->is_object() ? nullptr : &*it;
}

Response json_response(const nlohmann::json& body) {
  Response r;
  r.content_type = "application/json";
  r.body = body.dump();
  r.headers.emplace_back("Cache-Control", "no-store");
  return r;
}

std::string content_type_of(const fs::path& path) {
  const std::string ext = path.extension().string();
  if (ext == ".png") return "image/png";
  if (ext == ".jpg" || ext == ".jpeg") return "image/jpeg";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".json") return "application/json";
  if (ext == ".mp4") return "video/mp4";
  if (ext == ".csv" || ext == ".md" || ext == ".txt" || ext == ".toml") return "text/plain; charset=utf-8";
  return "application/octet-stream";
}

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// The number at `key` of a JSON object when it is an integer in [lo, hi].
bool integer_in(const nlohmann::json& j, const char* key, int64_t lo, int64_t hi, int64_t& out) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_number_integer()) return false;
  const int64_t v = it->get<int64_t>();
  if (v < lo || v > hi) return false;
  out = v;
  return true;
}

}  // namespace

bool percent_decode(const std::string& text, std::string& out) {
  out.clear();
  out.reserve(text.size());
  for (size_t i = 0; i < text.size(); ++i) {
    char c = text[i];
    if (c == '%') {
      if (i + 2 >= text.size()) return false;  // "%" or "%4" at the end
      const int hi = hex_value(text[i + 1]), lo = hex_value(text[i + 2]);
      if (hi < 0 || lo < 0) return false;
      c = static_cast<char>(hi * 16 + lo);
      i += 2;
    }
    if (c == '\0') return false;
    out.push_back(c);
  }
  return true;
}

std::string query_value(const std::string& query, const std::string& key) {
  size_t start = 0;
  while (start <= query.size()) {
    const size_t end = std::min(query.find('&', start), query.size());
    const std::string pair = query.substr(start, end - start);
    const size_t eq = pair.find('=');
    if (eq != std::string::npos && pair.compare(0, eq, key) == 0 && eq == key.size()) {
      std::string value;
      return percent_decode(pair.substr(eq + 1), value) ? value : std::string();
    }
    start = end + 1;
  }
  return {};
}

std::string resolve_inside(const std::string& root, const std::string& relative) {
  if (relative.empty() || relative.front() == '/' || relative.find('\0') != std::string::npos) return {};
  if (relative.find('\\') != std::string::npos) return {};
  const fs::path rel(relative);
  if (rel.is_absolute() || rel.has_root_name()) return {};
  for (const auto& part : rel) {
    if (part == "..") return {};
  }
  std::error_code ec;
  // canonical: every symlink resolved, so a link inside the run folder that points out of it is caught by the
  // prefix check below, as is anything `..`-like that slipped past the component check.
  const fs::path resolved = fs::canonical(fs::path(root) / rel, ec);
  if (ec) return {};
  const fs::path base(root);
  auto r = resolved.begin();
  for (auto b = base.begin(); b != base.end(); ++b, ++r) {
    if (r == resolved.end() || *r != *b) return {};
  }
  if (!fs::is_regular_file(resolved, ec) || ec) return {};
  return resolved.string();
}

bool same_secret(const std::string& a, const std::string& b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  const std::string& longer = a.size() >= b.size() ? a : b;
  for (size_t i = 0; i < longer.size(); ++i) {
    const unsigned char x = i < a.size() ? a[i] : 0, y = i < b.size() ? b[i] : 0;
    diff |= static_cast<unsigned char>(x ^ y);
  }
  return diff == 0;
}

Handler::Handler(HandlerOptions options, RenderBackend* backend)
    : options_(std::move(options)), port_(options_.bound.port), backend_(backend) {
  std::error_code ec;
  run_root_ = fs::canonical(options_.run_folder, ec).string();
}

Response Handler::handle(const Request& request) const {
  Response response = answer(request);
  // No other page may frame the viewer (a click on its buttons through an invisible frame), guess a type for a run
  // file, or learn the token from a Referer.
  response.headers.emplace_back("X-Frame-Options", "DENY");
  response.headers.emplace_back("Content-Security-Policy", "frame-ancestors 'none'");
  response.headers.emplace_back("X-Content-Type-Options", "nosniff");
  response.headers.emplace_back("Referrer-Policy", "no-referrer");
  return response;
}

Response Handler::answer(const Request& request) const {
  try {
    if (request.target.size() > options_.max_target_bytes) return text(414, "request target too long");
    if (request.body.size() > options_.max_body_bytes) return text(413, "request body too large");
    if (request.target.empty() || request.target.front() != '/') return text(400, "malformed request target");
    const size_t q = request.target.find('?');
    const std::string raw_path = request.target.substr(0, q);
    const std::string query = q == std::string::npos ? "" : request.target.substr(q + 1);
    std::string path;
    if (!percent_decode(raw_path, path)) return text(400, "malformed percent-encoding in the path");
    Response refused = refuse_foreign(request);
    if (refused.status != 0) return refused;
    if (!options_.token.empty() && !same_secret(query_value(query, "token"), options_.token)) {
      return text(403, "this viewer needs its token: open the URL `mipnerf-cl view` printed (…?token=…)");
    }
    return route(request.method, path, request);
  } catch (const std::exception& e) {  // a bug, not the client's fault: answer and keep serving
    return text(500, std::string("internal error: ") + e.what());
  } catch (...) {
    return text(500, "internal error");
  }
}

Response Handler::refuse_foreign(const Request& request) const {
  BoundAddress bound = options_.bound;
  bound.port = port_.load();
  if (!host_allowed(request.host, bound)) {
    return text(403, "this viewer answers only requests addressed to it (Host " + bound.host + ":" +
                         std::to_string(bound.port) + ", localhost or 127.0.0.1); open the URL `mipnerf-cl view` printed");
  }
  if (request.method == "GET" || request.method == "HEAD") return not_refused();
  // A request that changes state (renders, paths written into the run folder): never from another web page.
  if (!origin_allowed(request.origin, bound) || request.sec_fetch_site == "cross-site" ||
      request.sec_fetch_site == "same-site") {
    return text(403, "this viewer takes requests from its own page only, not from another origin");
  }
  if (!is_json_content_type(request.content_type)) {
    return text(415, "a request that changes state must be sent as Content-Type: application/json");
  }
  return not_refused();
}

Response Handler::route(const std::string& method, const std::string& path, const Request& request) const {
  if (method == "GET" && (path == "/" || path == "/index.html")) {
    Response r;
    r.content_type = "text/html; charset=utf-8";
    r.body = page_html();
    r.headers.emplace_back("Cache-Control", "no-store");
    return r;
  }
  RenderBackend* backend = backend_.load();
  if (method == "GET" && path == "/api/run") {
    std::error_code ec;
    const std::string root = run_root_.empty() ? fs::weakly_canonical(options_.run_folder, ec).string() : run_root_;
    nlohmann::json state = run_state(root);
    if (backend) state["viewer"] = to_json(backend->status());
    return json_response(state);
  }
  if (method == "GET" && path == "/api/cameras") {
    if (!backend) return no_checkpoint_yet();
    return json_response(to_json(backend->start_cameras()));
  }
  if (method == "GET" && path.rfind("/run/", 0) == 0) return serve_run_file(path.substr(5));
  if (method == "POST" && path == "/api/render") return render(request.body);
  if (method == "GET" && path == "/api/render/progress") {
    if (!backend) return no_checkpoint_yet();
    return json_response(to_json(backend->render_progress()));
  }
  if (path == "/api/path" || path == "/api/path/cancel") {
    if (!backend) return no_checkpoint_yet();
    if (method == "GET" && path == "/api/path") return json_response(to_json(backend->path_status()));
    if (method == "POST" && path == "/api/path") return start_path(request.body);
    if (method == "POST") {
      backend->cancel_path();
      return json_response(to_json(backend->path_status()));
    }
    return text(405, "method not allowed");
  }
  if (path == "/" || path == "/api/run" || path == "/api/cameras" || path == "/api/render" ||
      path == "/api/render/progress") {
    return text(405, "method not allowed");
  }
  return text(404, "not found: " + path.substr(0, 200));
}

Response Handler::serve_run_file(const std::string& relative) const {
  std::error_code ec;
  // The run folder as it was at the start, or (when `view` started before `train` made it) as it is now.
  const std::string root = run_root_.empty() ? fs::canonical(options_.run_folder, ec).string() : run_root_;
  if (root.empty()) return text(404, "the run folder does not exist (yet)");
  const std::string file = resolve_inside(root, relative);
  if (file.empty()) return text(404, "no such file in the run folder");
  const auto size = fs::file_size(file, ec);
  if (ec || size > options_.max_file_bytes) return text(413, "file too large to serve");
  std::ifstream in(file, std::ios::binary);
  Response r;
  r.body.resize(static_cast<size_t>(size));
  if (!in.read(r.body.data(), static_cast<std::streamsize>(size))) r.body.resize(static_cast<size_t>(in.gcount()));
  r.content_type = content_type_of(file);
  r.headers.emplace_back("Cache-Control", "no-cache");
  return r;
}

Response Handler::render(const std::string& body) const {
  const nlohmann::json j = nlohmann::json::parse(body, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return text(400, "the render request is not a JSON object");
  RenderRequest req;
  int64_t divisor = 0, generation = 0;
  if (!integer_in(j, "divisor", 1, 64, divisor)) return text(400, "'divisor' must be an integer in 1..64");
  if (!integer_in(j, "generation", 0, INT64_MAX, generation)) return text(400, "'generation' must be an integer >= 0");
  req.divisor = static_cast<int>(divisor);
  req.generation = static_cast<uint64_t>(generation);
  if (j.contains("output")) {
    if (!j["output"].is_string() || !parse_render_output(j["output"].get<std::string>(), req.output)) {
      return text(400, "'output' must be rgb, depth or acc");
    }
  }
  const nlohmann::json* camera = object_at(j, "camera");
  if (!camera) return text(400, "'camera' must be a camera path object");
  RenderBackend* backend = backend_.load();
  if (!backend) return no_checkpoint_yet();
  try {
    req.camera = page_camera(*camera, backend->camera_defaults());
  } catch (const Error& e) {
    return text(400, e.what());
  }
  const RenderReply reply = backend->render(req);
  switch (reply.status) {
    case RenderReply::Status::ok: {
      Response r;
      r.content_type = "image/png";
      r.body = reply.png;
      r.headers.emplace_back("Cache-Control", "no-store");
      r.headers.emplace_back("X-Render-Seconds", std::to_string(reply.seconds));
      r.headers.emplace_back("X-Render-Size", std::to_string(reply.width) + "x" + std::to_string(reply.height));
      r.headers.emplace_back("X-Render-Step", std::to_string(reply.step));
      return r;
    }
    case RenderReply::Status::superseded: return text(409, "superseded by a newer view");
    case RenderReply::Status::busy: return text(503, reply.message.empty() ? "too many renders waiting" : reply.message);
    case RenderReply::Status::bad_request: return text(400, reply.message);
    case RenderReply::Status::failed: return text(500, reply.message);
  }
  return text(500, "unknown render status");
}

Response Handler::start_path(const std::string& body) const {
  const nlohmann::json j = nlohmann::json::parse(body, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return text(400, "the path request is not a JSON object");
  PathRequest req;
  int64_t frames = 0, divisor = 0;
  if (!integer_in(j, "frames", 1, 3600, frames)) return text(400, "'frames' must be an integer in 1..3600");
  if (!integer_in(j, "divisor", 1, 64, divisor)) return text(400, "'divisor' must be an integer in 1..64");
  req.frames = static_cast<uint32_t>(frames);
  req.divisor = static_cast<int>(divisor);
  if (j.contains("fps")) {
    const auto& fps = j["fps"];
    if (!fps.is_number() || !(fps.get<double>() > 0.0 && fps.get<double>() <= 120.0)) {
      return text(400, "'fps' must be a number in (0, 120]");
    }
    req.fps = fps.get<double>();
  }
  const nlohmann::json* keyframes = object_at(j, "keyframes");
  if (!keyframes) return text(400, "'keyframes' must be a camera path object");
  RenderBackend* backend = backend_.load();
  if (!backend) return no_checkpoint_yet();
  try {
    req.keyframes = recorded_keyframes(*keyframes, backend->camera_defaults());
  } catch (const Error& e) {
    return text(400, e.what());
  }
  const PathReply reply = backend->start_path(req);
  switch (reply.status) {
    case PathReply::Status::started: {
      Response r = json_response(to_json(backend->path_status()));
      r.status = 202;
      return r;
    }
    case PathReply::Status::busy: return text(409, reply.message);
    case PathReply::Status::bad_request: return text(400, reply.message);
  }
  return text(500, "unknown path status");
}

}  // namespace mipnerf::view
