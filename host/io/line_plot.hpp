// Line plots as SVG or PNG files (the curves of `mipnerf-cl plot`), drawn by PLplot: its built-in SVG driver, and
// its cairo driver for PNG (Debian plplot-driver-cairo). A packaged plotting library rather than a writer of our
// own because a PNG needs text rasterised (axis numbers, labels, the legend), which is a font renderer's work.
#pragma once

#include <string>
#include <vector>

namespace mipnerf::io {

struct PlotSeries {
  std::string label;      // the legend's text
  std::vector<double> x;  // same length as y, at least one point
  std::vector<double> y;
};

struct LinePlot {
  std::string title;
  std::string x_label;
  std::string y_label;
  bool log_x = false;  // a logarithmic x axis (every x must then be > 0)
  std::vector<PlotSeries> series;
  int width_px = 1000;  // the page: pixels for PNG, points for SVG
  int height_px = 560;
};

// The axes' ranges: x from its smallest to its largest value (from 0 when all x ≥ 0 on a linear axis), y padded by
// 5 % of its span (at least 0.5) so no curve lies on the frame. Throws mipnerf::Error for an empty plot, series of
// unequal lengths, non-finite values, or x ≤ 0 on a log axis, naming the series.
struct PlotRanges {
  double x_min = 0, x_max = 1, y_min = 0, y_max = 1;
};
PlotRanges plot_ranges(const LinePlot& plot);

// Throws mipnerf::Error unless `path` names a picture write_line_plot writes (.svg or .png, any case): a check to
// make before gathering what to plot.
void check_plot_path(const std::string& path);

// Writes `plot` to `path` atomically; the format follows the extension (.svg or .png, any case). Throws
// mipnerf::Error for another extension, a PNG without PLplot's cairo driver (naming the package), or an invalid
// plot (plot_ranges).
void write_line_plot(const std::string& path, const LinePlot& plot);

}  // namespace mipnerf::io
