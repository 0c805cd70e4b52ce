// The viewer's HTTP server: cpp-httplib (Debian's libcpp-httplib-dev) parses HTTP and hands every request to a
// view::Handler; no route logic lives here.
#pragma once

#include <memory>
#include <string>

#include "view/handler.hpp"

namespace mipnerf::view {

struct ServerOptions {
  std::string host = "127.0.0.1";
  int port = 8000;  // 0: any free port (port() says which)
  int threads = 8;  // concurrent connections (renders are bounded by the renderer, not here)
};

class HttpServer {
 public:
  // Binds; throws mipnerf::Error naming the address when it cannot (in use, no such address).
  HttpServer(const Handler& handler, const ServerOptions& options);
  ~HttpServer();
  int port() const;
  void run();   // serves until stop()
  void stop();  // from another thread

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mipnerf::view
