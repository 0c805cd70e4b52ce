// Global options and the shared device opening of the CLI.
#include "common.hpp"


#include <iostream>

#include "core/error.hpp"
#include "mlp/gemm_backend.hpp"
#include "mlp/gemm_tuning.hpp"

namespace mipnerf::cli {

GlobalOptions& global_options() {
  static GlobalOptions options;
  return options;
}

void print_log(LogLevel level, const std::string& message) {
  if (level == LogLevel::debug && !global_options().verbose) return;
  const char* prefix = level == LogLevel::warning ? "warning: " : level == LogLevel::debug ? "debug: " : "";
  std::cerr << "mipnerf-cl: " << prefix << message << "\n";
}

std::unique_ptr<ocl::Context> open_context(bool profiling) {
  ocl::ContextOptions options;
  options.device_selector = global_options().device;
  options.profiling = profiling;
  auto ctx = ocl::Context::create(options);
  ctx->set_log(print_log);
  ctx->log(LogLevel::debug, "using device [" + std::to_string(ctx->device_info().index) + "] " +
                                ctx->device_info().name);
  return ctx;
}

void check_view_options(const CLI::App& cmd, size_t views, int scales, uint32_t supersample) {
  if (cmd.count("--views") && views == 0) throw Error("--views must be at least 1 (leave it out for all views)");
  if (cmd.count("--scales") && scales < 1) throw Error("--scales must be at least 1");
  if (supersample == 0) throw Error("--supersample must be at least 1 ray per pixel");
}

std::map<std::string, std::string> parse_set_assignments(const std::vector<std::string>& assignments,
                                                         const std::string& example) {
  std::map<std::string, std::string> out;
  for (const auto& assignment : assignments) {
    const auto eq = assignment.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw Error("--set '" + assignment + "': expected name=value, e.g. --set " + example);
    }
    out[assignment.substr(0, eq)] = assignment.substr(eq + 1);
  }
  return out;
}

void prepare_gemm_for_rendering(ocl::Context& ctx) {
  mlp::load_gemm_tuning(ctx);
  mlp::use_gemm_backend(ctx, mlp::GemmBackend::automatic);
}

}  // namespace mipnerf::cli
