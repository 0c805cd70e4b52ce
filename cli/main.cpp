// mipnerf-cl: the command-line tool. Sets up the subcommands and turns every error into one line.
#include <iostream>

#include <CLI/CLI.hpp>

#include "core/error.hpp"
#include "data/path_policy.hpp"
#include "io/image_budget.hpp"
#include "common.hpp"
#include "parallel/world.hpp"
#include "planted_fault.hpp"

namespace mipnerf::cli {
namespace {

// CLI11 reports a mistyped command as "A subcommand is required"; name the word and the commands.
std::string describe_parse_error(CLI::App& app, const CLI::ParseError& e, int argc, char** argv) {
  if (app.get_subcommands().empty() && argc > 1 && argv[1][0] != '-') {
    std::string names;
    for (const auto* sub : app.get_subcommands({})) names += (names.empty() ? "" : ", ") + sub->get_name();
    return std::string("unknown command '") + argv[1] + "'; the commands are: " + names;
  }
  return std::string(e.what()) + " (see mipnerf-cl --help)";
}

}  // namespace
}  // namespace mipnerf::cli

int main(int argc, char** argv) {
  using namespace mipnerf;
  cli::plant_fault_if_asked();  // test-only, sanitizer build only (planted_fault.hpp)
  CLI::App app{"mipnerf-cl: anti-aliased neural radiance fields (mip-NeRF) on any OpenCL device"};
  app.formatter(std::make_shared<cli::HelpFormatter>());  // before the subcommands, which take their parent's
  app.set_version_flag("--version", std::string("mipnerf-cl ") + MIPNERF_VERSION);
  auto& global = cli::global_options();
  app.add_option("--device", global.device,
                 "OpenCL device: index or part of its or its platform's name (default: $MIPNERF_DEVICE, else the "
                 "first GPU, else the first CPU)")
      ->envname("MIPNERF_DEVICE");
  app.add_flag("-v,--verbose", global.verbose, "Print debug messages and full kernel build logs");
  app.add_option_function<uint64_t>(
         "--max-image-mib", [](uint64_t mib) { io::set_image_budget_bytes(mib << 20); },
         "The most memory one image's decode may take, in MiB (default 2048): a PNG or JPEG whose header declares "
         "more is refused before anything is allocated for it")
      ->envname("MIPNERF_MAX_IMAGE_MIB")
      ->check(CLI::Range(uint64_t{1}, uint64_t{1} << 24));
  app.add_flag_callback(
      "--allow-outside-paths", [] { data::set_outside_paths_allowed(true); },
      "Let a dataset's files (transforms.json, metadata.json, a COLMAP model) name images outside its folder (absolute "
      "paths, or ../): refused by default, so a downloaded dataset cannot make the tool read your other files");
  app.require_subcommand(1);
  // Global options may follow the subcommand: `mipnerf-cl devices --device 1`.
  app.fallthrough();

  cli::register_devices(app);
  cli::register_tune(app);
  cli::register_train(app);
  cli::register_dataset(app);
  cli::register_make_scene(app);
  cli::register_make_multiscale(app);
  cli::register_render(app);
  cli::register_eval(app);
  cli::register_bench(app);
  cli::register_plot(app);
  cli::register_view(app);
  // Under mpirun only train, render and eval share the work between ranks; the other commands would run N times
  // over the same files.
  for (CLI::App* sub : app.get_subcommands({})) {
    const std::string name = sub->get_name();
    if (name == "train" || name == "render" || name == "eval") continue;
    sub->preparse_callback([name](size_t) {
      if (parallel::world().distributed()) {
        throw parallel::CollectiveError("mipnerf-cl " + name + " runs as one process: start it without mpirun (train, "
                                    "render and eval run under mpirun)");
      }
    });
  }

  try {
    // First: under mpirun this process is one rank of several (host/parallel); the session ends MPI on every return.
    parallel::Session session(&argc, &argv);
    try {
      app.parse(argc, argv);
    } catch (const CLI::Error&) {
      throw;
    } catch (const std::exception& e) {
      cli::report_error(e);
      // An error of this rank alone leaves the others waiting in the next collective: stop them all.
      if (dynamic_cast<const parallel::CollectiveError*>(&e) == nullptr) parallel::Session::abort_all(1);
      return 1;
    }
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // One line, like every other error: what was wrong, and where to look.
    std::cerr << "mipnerf-cl: error: " << cli::describe_parse_error(app, e, argc, argv) << "\n";
    return e.get_exit_code();
  } catch (const Error& e) {
    cli::report_error(e);
    return 1;
  } catch (const std::exception& e) {
    cli::report_error(e);
    return 1;
  }
  return 0;
}
