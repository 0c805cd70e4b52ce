// Curves of training runs from their folders: the val scores train wrote every val_every steps (val_log.csv), as
// series for io::write_line_plot (`mipnerf-cl plot`).
#pragma once

#include <string>
#include <vector>

#include "io/line_plot.hpp"

namespace mipnerf::eval {

enum class CurveX { train_seconds, steps };

// The val PSNR of the run in `run_dir` against its training seconds (val time excluded) or its steps, labelled with
// the folder's name and the variant config.json records. Throws mipnerf::Error naming the file when the folder has
// no val_log.csv (with the setting that writes one), or when a row is malformed.
io::PlotSeries val_psnr_curve(const std::string& run_dir, CurveX x);

// The plot of several runs' curves, with axis labels for `x`.
io::LinePlot val_psnr_plot(const std::vector<std::string>& run_dirs, CurveX x, const std::string& title);

}  // namespace mipnerf::eval
