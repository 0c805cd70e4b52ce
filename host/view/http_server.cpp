// cpp-httplib around the viewer's handler.
#include "view/http_server.hpp"

#include <httplib.h>

#include "core/error.hpp"

namespace mipnerf::view {
namespace {

// Everything a request's header block may hold, names and values: a browser's requests to the viewer are < 2 KB.
constexpr size_t kMaxHeaderBytes = 16 << 10;

void refuse(httplib::Response& res, int status, const std::string& message) {
  res.status = status;
  res.set_content(message + "\n", "text/plain; charset=utf-8");
  res.set_header("Connection", "close");
}

// Before cpp-httplib reads a body or routes: what it would otherwise do unbounded. It inflates a gzip or brotli body
// whole before anyone can look at it (a 1.7 KB brotli body became 1 GiB in memory), and answers each of any number of
// byte ranges with a copy (2,000 ranges of "0-" made a 1.3 KB file a 2.9 MB answer; of a 64 MB video, 128 GB) under
// the status the handler set (200 for a part of the file). Ranges are ignored, as HTTP lets a server do: every answer
// is the whole file, with 200.
httplib::Server::HandlerResponse guard(const httplib::Request& req, httplib::Response& res) {
  size_t header_bytes = 0;
  for (const auto& [name, value] : req.headers) header_bytes += name.size() + value.size() + 4;
  if (header_bytes > kMaxHeaderBytes) {
    refuse(res, 431, "request header fields too large");
    return httplib::Server::HandlerResponse::Handled;
  }
  if (req.has_header("Content-Encoding") && req.get_header_value("Content-Encoding") != "identity") {
    refuse(res, 415, "a compressed request body is not accepted: send it as plain JSON");
    return httplib::Server::HandlerResponse::Handled;
  }
  // The request is cpp-httplib's own non-const object, handed to this hook as const.
  const_cast<httplib::Request&>(req).ranges.clear();
  return httplib::Server::HandlerResponse::Unhandled;
}

// The request as the handler reads it; its body (already read, or read here by `reader` up to `max_body_bytes`).
Request request_of(const httplib::Request& req) {
  Request request;
  request.method = req.method;
  request.target = req.target;
  // A header sent more than once is passed on empty, which fails the checks that need it (view/request_guard.hpp).
  auto only = [&req](const char* name) {
    return req.get_header_value_count(name) == 1 ? req.get_header_value(name) : std::string();
  };
  request.host = only("Host");
  request.origin = only("Origin");
  request.content_type = only("Content-Type");
  request.sec_fetch_site = only("Sec-Fetch-Site");
  return request;
}

void respond(const Handler& handler, const Request& request, httplib::Response& res) {
  const Response response = handler.handle(request);
  res.status = response.status;
  for (const auto& [name, value] : response.headers) res.set_header(name, value);
  res.set_content(response.body, response.content_type);
}

}  // namespace

struct HttpServer::Impl {
  httplib::Server server;
  int port = 0;
};

HttpServer::HttpServer(const Handler& handler, const ServerOptions& options) : impl_(std::make_unique<Impl>()) {
  httplib::Server& server = impl_->server;
  const int threads = options.threads;
  const size_t max_body = handler.options().max_body_bytes;
  server.new_task_queue = [threads] { return new httplib::ThreadPool(static_cast<size_t>(threads)); };
  server.set_payload_max_length(max_body);  // a declared Content-Length above it: 413 before reading
  server.set_read_timeout(10, 0);
  server.set_write_timeout(30, 0);
  server.set_pre_routing_handler(guard);
  auto serve = [&handler](const httplib::Request& req, httplib::Response& res) {
    respond(handler, request_of(req), res);
  };
  // Bodies read here, bounded as they arrive (a chunked body declares no length).
  auto serve_with_body = [&handler, max_body](const httplib::Request& req, httplib::Response& res,
                                              const httplib::ContentReader& reader) {
    Request request = request_of(req);
    // A body the handler refuses anyway (not JSON: 415) is not read; one declared too long is refused unread.
    if (!is_json_content_type(request.content_type)) return respond(handler, request, res);
    if (req.get_header_value<uint64_t>("Content-Length") > max_body) return refuse(res, 413, "request body too large");
    bool too_large = false;
    const bool read = reader([&](const char* data, size_t length) {
      if (request.body.size() + length > max_body) {
        too_large = true;
        return false;
      }
      request.body.append(data, length);
      return true;
    });
    if (too_large) return refuse(res, 413, "request body too large");
    if (!read) return refuse(res, 400, "the request body could not be read");
    respond(handler, request, res);
  };
  server.Get(".*", serve);
  server.Post(".*", serve_with_body);
  server.Put(".*", serve_with_body);
  server.Delete(".*", serve);
  server.Options(".*", serve);
  if (options.port == 0) {
    impl_->port = server.bind_to_any_port(options.host);
    if (impl_->port < 0) throw Error(options.host + ": cannot listen on this address (give --host 127.0.0.1)");
  } else {
    if (!server.bind_to_port(options.host, options.port)) {
      throw Error(options.host + ":" + std::to_string(options.port) +
                  ": cannot listen there (the port is in use or the address is not this machine's): give another "
                  "--port or --host");
    }
    impl_->port = options.port;
  }
}

HttpServer::~HttpServer() = default;

int HttpServer::port() const { return impl_->port; }

void HttpServer::run() { impl_->server.listen_after_bind(); }

void HttpServer::stop() { impl_->server.stop(); }

}  // namespace mipnerf::view
