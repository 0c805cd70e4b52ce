// cpp-httplib around the viewer's handler.
#include "view/http_server.hpp"

#include <httplib.h>

#include "core/error.hpp"

namespace mipnerf::view {

struct HttpServer::Impl {
  httplib::Server server;
  int port = 0;
};

HttpServer::HttpServer(const Handler& handler, const ServerOptions& options) : impl_(std::make_unique<Impl>()) {
  httplib::Server& server = impl_->server;
  const int threads = options.threads;
  server.new_task_queue = [threads] { return new httplib::ThreadPool(static_cast<size_t>(threads)); };
  server.set_payload_max_length(handler.options().max_body_bytes);
  server.set_read_timeout(10, 0);
  server.set_write_timeout(30, 0);
  auto serve = [&handler](const httplib::Request& req, httplib::Response& res) {
    Request request;
    request.method = req.method;
    request.target = req.target;
    request.body = req.body;
    const Response response = handler.handle(request);
    res.status = response.status;
    for (const auto& [name, value] : response.headers) res.set_header(name, value);
    res.set_content(response.body, response.content_type);
  };
  server.Get(".*", serve);
  server.Post(".*", serve);
  server.Put(".*", serve);
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
