// `mipnerf-cl plot RUN... --out PATH`: val PSNR against training time (or steps) of training runs, from their
// val_log.csv (train --set val_every=N), as SVG or PNG.
#include <iostream>
#include <memory>

#include "common.hpp"
#include "eval/run_curves.hpp"
#include "io/line_plot.hpp"

namespace mipnerf::cli {

void register_plot(CLI::App& app) {
  struct Args {
    std::vector<std::string> runs;
    std::string out, title, x = "seconds";
    bool log_x = false;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "plot",
      "Draw val PSNR against training seconds (or steps) of training runs, from the val scores train "
      "writes every val_every steps (OUT/val_log.csv), as SVG or PNG");
  cmd->add_option("RUN", args->runs, "Training run folders (train --out), one curve each")->required();
  cmd->add_option("--out", args->out, "The picture to write: .svg or .png")->required();
  cmd->add_option("--x", args->x, "What the x axis shows: seconds (training, val scoring excluded) or steps")
      ->check(CLI::IsMember({"seconds", "steps"}))
      ->capture_default_str();
  cmd->add_option("--title", args->title, "Title above the plot");
  cmd->add_flag("--log-x", args->log_x, "A logarithmic x axis");
  cmd->callback([args] {
    io::check_plot_path(args->out);  // before reading the runs: a wrong --out is said first
    const auto x = args->x == "steps" ? eval::CurveX::steps : eval::CurveX::train_seconds;
    io::LinePlot plot = eval::val_psnr_plot(args->runs, x, args->title);
    plot.log_x = args->log_x;
    io::write_line_plot(args->out, plot);
    std::cout << "wrote " << args->out << " (" << plot.series.size() << " curve" << (plot.series.size() == 1 ? "" : "s")
              << ")\n";
  });
}

}  // namespace mipnerf::cli
