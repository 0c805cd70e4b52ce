// What every subcommand shares: the global options, opening the device, --set parsing, a scratch folder, and
// printing to the terminal.
#pragma once

#include <cstddef>
#include <cstdint>
#include <exception>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "cl/context.hpp"

namespace mipnerf::cli {

struct GlobalOptions {
  std::string device;    // --device: index or name substring
  bool verbose = false;  // --verbose: debug messages and full build logs
};

GlobalOptions& global_options();

// Opens the device chosen by --device, with the library's log routed to stderr.
// Commands that run GEMMs then call gemm::load_gemm_tuning once their inputs are checked.
std::unique_ptr<ocl::Context> open_context(bool profiling = false);

// The view selection and sampling options that render and eval share (--views, --scales, --supersample):
// throws mipnerf::Error naming the flag when one is out of range. --views and --scales are checked only when given.
void check_view_options(const CLI::App& cmd, size_t views, int scales, uint32_t supersample);

// --set name=value assignments as a map, later ones winning; throws mipnerf::Error naming a malformed one, with
// `example` ("num_samples=64") to show the form.
std::map<std::string, std::string> parse_set_assignments(const std::vector<std::string>& assignments,
                                                         const std::string& example);

// Prints an error as one line ("mipnerf-cl: error: …", with the rank under mpirun); a parallel::CollectiveError, which
// every rank raises alike, is printed by rank 0 alone. Details follow with --verbose.
void report_error(const std::exception& e);

// Prints a library log message to stderr ("mipnerf-cl: warning: ..."); under mpirun, info only from rank 0.
void print_log(LogLevel level, const std::string& message);

// Each subcommand registers itself on the app; main() calls them all.
void register_devices(CLI::App& app);
void register_tune(CLI::App& app);
void register_train(CLI::App& app);
void register_dataset(CLI::App& app);
void register_make_scene(CLI::App& app);
void register_make_multiscale(CLI::App& app);
void register_render(CLI::App& app);
void register_eval(CLI::App& app);
void register_bench(CLI::App& app);
void register_plot(CLI::App& app);
void register_view(CLI::App& app);

}  // namespace mipnerf::cli
