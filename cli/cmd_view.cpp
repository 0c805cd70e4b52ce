// `mipnerf-cl view RUN`: a local web page that follows a run (its settings, progress, curves and val images, live
// while `train` writes the folder) and renders any viewpoint of its newest checkpoint progressively on the device.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <random>
#include <thread>

#include "common.hpp"
#include "core/error.hpp"
#include "interrupt.hpp"
#include "train/checkpoint.hpp"
#include "view/handler.hpp"
#include "view/http_server.hpp"
#include "view/view_renderer.hpp"

namespace mipnerf::cli {
namespace fs = std::filesystem;
namespace {

struct ViewArgs {
  std::string run;
  std::string host = "127.0.0.1";
  int port = 8000;
  std::string token;
  size_t max_waiting = 4;
};

bool is_loopback(const std::string& host) {
  return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

// 128 random bits as hex: the token a non-local viewer requires.
std::string random_token() {
  std::random_device device;
  std::string token;
  const char* digits = "0123456789abcdef";
  for (int i = 0; i < 32; ++i) token.push_back(digits[device() % 16]);
  return token;
}

// The renderer, once the run has a checkpoint that loads (train may still be starting); null until then.
std::unique_ptr<view::ViewRenderer> try_renderer(ocl::Context& ctx, const view::ViewRendererOptions& options,
                                                 std::string& last_error) {
  const fs::path run(options.run_folder);
  if (train::list_checkpoints((run / "checkpoints").string()).empty() && train::list_checkpoints(run.string()).empty()) {
    return nullptr;
  }
  try {
    return std::make_unique<view::ViewRenderer>(ctx, options);
  } catch (const Error& e) {
    if (last_error != e.what()) std::cerr << "mipnerf-cl: warning: " << e.what() << " (trying again)\n";
    last_error = e.what();
    return nullptr;
  }
}

void run_view(const ViewArgs& args) {
  std::error_code ec;
  if (fs::exists(args.run, ec) && !fs::is_directory(args.run, ec)) {
    throw Error(args.run + ": not a folder (give the --out folder of `mipnerf-cl train`)");
  }
  if (args.port < 0 || args.port > 65535) throw Error("--port must lie in 0..65535 (0: any free port)");
  std::string token = args.token;
  if (!is_loopback(args.host)) {
    if (token.empty()) token = random_token();
    std::cerr << "mipnerf-cl: warning: --host " << args.host
              << " serves the run to other machines: anyone who can reach this port and has the token can see it; "
                 "there is no TLS\n";
  }
  auto ctx = open_context();
  view::ViewRendererOptions render_options;
  render_options.run_folder = args.run;
  render_options.max_waiting = args.max_waiting;
  std::string last_error;
  std::unique_ptr<view::ViewRenderer> renderer = try_renderer(*ctx, render_options, last_error);
  view::HandlerOptions handler_options;
  handler_options.run_folder = args.run;
  handler_options.token = token;
  handler_options.bound.host = args.host;
  handler_options.bound.port = args.port;
  view::Handler handler(handler_options, renderer.get());
  view::ServerOptions server_options;
  server_options.host = args.host;
  server_options.port = args.port;
  view::HttpServer server(handler, server_options);
  handler.set_port(server.port());  // --port 0: the port the system gave

  const std::string shown_host = args.host.find(':') != std::string::npos ? "[" + args.host + "]" : args.host;
  const std::string what = renderer ? "step " + std::to_string(renderer->step()) : "no checkpoint yet";
  std::printf("viewing %s (%s on %s) at http://%s:%d/%s\nCtrl-C stops\n", args.run.c_str(), what.c_str(),
              ctx->device_info().name.c_str(), shown_host.c_str(), server.port(),
              token.empty() ? "" : ("?token=" + token).c_str());
  std::fflush(stdout);
  StopOnInterrupt stop;
  std::thread serving([&server] { server.run(); });
  // Until the run's first checkpoint loads, the page shows the run's logs and waits for renders.
  auto next_try = std::chrono::steady_clock::now();
  while (!StopOnInterrupt::requested()) {
    if (!renderer && std::chrono::steady_clock::now() >= next_try) {
      renderer = try_renderer(*ctx, render_options, last_error);
      if (renderer) {
        handler.set_backend(renderer.get());
        std::printf("rendering step %lld\n", static_cast<long long>(renderer->step()));
        std::fflush(stdout);
      }
      next_try = std::chrono::steady_clock::now() + std::chrono::seconds(1);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  server.stop();
  serving.join();
  std::printf("stopped\n");
}

}  // namespace

void register_view(CLI::App& app) {
  auto args = std::make_shared<ViewArgs>();
  auto* cmd = app.add_subcommand(
      "view", "Serve a web page that follows a run live and renders any viewpoint of it progressively");
  cmd->add_option("run", args->run, "The run folder (train --out)")->required();
  cmd->add_option("--port", args->port, "TCP port (0: any free port)")->capture_default_str();
  cmd->add_option("--host", args->host,
                  "Address to listen on; anything but loopback prints a warning and requires a token in the URL")
      ->capture_default_str();
  cmd->add_option("--token", args->token, "The token the URL must carry (default: random, when not on loopback)");
  cmd->add_option("--max-waiting", args->max_waiting, "Renders that may wait for the device beside the one running")
      ->capture_default_str();
  cmd->callback([args] { run_view(*args); });
}

}  // namespace mipnerf::cli
