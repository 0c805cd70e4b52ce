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
// (A network that runs its products on CLBlast loads the device's tuned parameters itself: mlp::make_network.)
std::unique_ptr<ocl::Context> open_context(bool profiling = false);

// The view selection and sampling options that render and eval share (--views, --scales, --supersample):
// throws mipnerf::Error naming the flag when one is out of range. --views and --scales are checked only when given.
void check_view_options(const CLI::App& cmd, size_t views, int scales, uint32_t supersample);

// --set name=value assignments as a map, later ones winning; throws mipnerf::Error naming a malformed one, with
// `example` ("num_samples=64") to show the form.
std::map<std::string, std::string> parse_set_assignments(const std::vector<std::string>& assignments,
                                                         const std::string& example);

// A setting's flag names for CLI11: "--val-every,--val_every" (dashes, as every other flag, and the setting's own
// name), or "--steps" for a name without '_'. --help shows the dash form alone (HelpFormatter).
std::string setting_flag_names(const std::string& setting);

// --help's formatter: an option that has both spellings of a name (--val-every, --val_every) shows the dash form.
class HelpFormatter : public CLI::Formatter {
 public:
  std::string make_option_name(const CLI::Option* option, bool is_positional) const override;
};

// Creates the output folder `path` given by `flag` (and its parents), or throws a one-line mipnerf::Error naming
// them, why, and what to do.
void make_output_folder(const std::string& path, const std::string& flag);

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
