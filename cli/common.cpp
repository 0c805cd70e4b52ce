// Global options and the shared device opening of the CLI.
#include "common.hpp"

#include <algorithm>
#include <filesystem>
#include <iostream>

#include "core/error.hpp"
#include "parallel/world.hpp"

namespace mipnerf::cli {

GlobalOptions& global_options() {
  static GlobalOptions options;
  return options;
}

namespace {

// "mipnerf-cl: ", or "mipnerf-cl (rank 1): " on ranks other than 0 under mpirun.
std::string line_prefix() {
  const parallel::World& w = parallel::world();
  return w.is_root() ? "mipnerf-cl: " : "mipnerf-cl (rank " + std::to_string(w.rank()) + "): ";
}

// One entry of a comma-separated --device list per local rank: "0,1" gives local rank 1 device 1.
std::string device_of_this_rank(const std::string& selector) {
  if (selector.find(',') == std::string::npos) return selector;
  std::vector<std::string> entries;
  size_t start = 0;
  for (size_t comma; (comma = selector.find(',', start)) != std::string::npos; start = comma + 1) {
    entries.push_back(selector.substr(start, comma - start));
  }
  entries.push_back(selector.substr(start));
  // Every rank reads the same list: what is wrong with the list itself, all of them find (a collective error).
  for (const auto& entry : entries) {
    if (entry.empty()) {
      throw parallel::CollectiveError("--device '" + selector + "': an empty entry in the list; give one device per "
                                  "local rank, e.g. --device 0,1");
    }
  }
  const parallel::World& w = parallel::world();
  if (!w.distributed()) {
    throw Error("--device '" + selector + "' lists several devices, one per rank under mpirun; this process runs "
                "alone: give one device");
  }
  // Hosts may hold different numbers of ranks: only those of a crowded host find this, so it stops the job.
  if (static_cast<int>(entries.size()) < w.local_size()) {
    throw Error("--device '" + selector + "' lists " + std::to_string(entries.size()) + " devices for " +
                std::to_string(w.local_size()) +
                " ranks on this host: list one per local rank, or one device that they share");
  }
  return entries[static_cast<size_t>(w.local_rank())];
}

}  // namespace

void report_error(const std::exception& e) {
  const bool collective = dynamic_cast<const parallel::CollectiveError*>(&e) != nullptr;
  // Every rank has it; rank 0 says it once (also among the copies mpirun started of a build without MPI).
  if (collective && !(parallel::world().is_root() && parallel::launcher_rank() == 0)) return;
  std::cerr << line_prefix() << "error: " << e.what() << "\n";
  const auto* error = dynamic_cast<const Error*>(&e);
  if (error != nullptr && global_options().verbose && !error->details().empty()) std::cerr << error->details() << "\n";
}

void print_log(LogLevel level, const std::string& message) {
  if (level == LogLevel::debug && !global_options().verbose) return;
  // Under mpirun the ranks do the same work: rank 0 tells it, the others only warn.
  if (level == LogLevel::info && !parallel::world().is_root()) return;
  const char* prefix = level == LogLevel::warning ? "warning: " : level == LogLevel::debug ? "debug: " : "";
  std::cerr << line_prefix() << prefix << message << "\n";
}

std::unique_ptr<ocl::Context> open_context(bool profiling) {
  ocl::ContextOptions options;
  options.device_selector = device_of_this_rank(global_options().device);
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

std::string setting_flag_names(const std::string& setting) {
  std::string dashed = setting;
  std::replace(dashed.begin(), dashed.end(), '_', '-');
  return dashed == setting ? "--" + setting : "--" + dashed + ",--" + setting;
}

std::string HelpFormatter::make_option_name(const CLI::Option* option, bool is_positional) const {
  const std::vector<std::string>& long_names = option->get_lnames();
  auto has_dash_twin = [&](const std::string& name) {
    std::string dashed = name;
    std::replace(dashed.begin(), dashed.end(), '_', '-');
    return dashed != name && std::find(long_names.begin(), long_names.end(), dashed) != long_names.end();
  };
  if (is_positional || std::none_of(long_names.begin(), long_names.end(), has_dash_twin)) {
    return CLI::Formatter::make_option_name(option, is_positional);
  }
  std::string names;
  for (const auto& name : option->get_snames()) names += (names.empty() ? "-" : ", -") + name;
  for (const auto& name : long_names) {
    if (!has_dash_twin(name)) names += (names.empty() ? "--" : ", --") + name;
  }
  return names;
}

void make_output_folder(const std::string& path, const std::string& flag) {
  namespace fs = std::filesystem;
  std::error_code ec, ignored;
  fs::create_directories(path, ec);
  if (fs::is_directory(path, ignored)) return;
  const std::string why = fs::exists(path, ignored) ? "a file of that name is in the way"
                          : ec                      ? ec.message()
                                                    : "it is not there after creating it";
  throw Error(flag + " " + path + ": cannot create this folder (" + why + "); give " + flag +
              " a folder you can write to");
}

}  // namespace mipnerf::cli
