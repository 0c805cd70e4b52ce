// PLplot behind io::write_line_plot: one plot stream per call, made, drawn and ended here.
#include "io/line_plot.hpp"

#ifdef MIPNERF_HAVE_PLPLOT
#include <plplot.h>
#endif

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <mutex>

#include "core/error.hpp"
#include "io/atomic_file.hpp"

namespace mipnerf::io {
namespace {

// Colours a white page shows well (PLplot's default map has yellow and wheat), then the same with dashes.
constexpr int kColours[][3] = {{31, 119, 180}, {255, 127, 14},  {44, 160, 44},   {214, 39, 40},  {148, 103, 189},
                               {140, 86, 75},  {227, 119, 194}, {127, 127, 127}, {188, 189, 34}, {23, 190, 207}};
constexpr int kColourCount = sizeof(kColours) / sizeof(kColours[0]);
constexpr int kInk = 15;   // map-0 index of the frame, numbers and text: black
constexpr int kGrid = 14;  // map-0 index of the grid: light grey

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// PLplot's driver for the picture `path` names.
const char* driver_for(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".svg") return "svg";
  if (ext == ".png") return "pngcairo";
  throw Error(path + ": a plot is written as .svg or .png; '" + ext + "' is neither");
}

void check_series(const PlotSeries& s, bool log_x) {
  const std::string where = "plot series '" + s.label + "'";
  if (s.x.empty() || s.x.size() != s.y.size()) {
    throw Error(where + ": " + std::to_string(s.x.size()) + " x and " + std::to_string(s.y.size()) +
                " y values; need the same number, at least one");
  }
  for (size_t i = 0; i < s.x.size(); ++i) {
    if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
      throw Error(where + ": point " + std::to_string(i) + " is not finite");
    }
    if (log_x && !(s.x[i] > 0)) throw Error(where + ": x = " + std::to_string(s.x[i]) + " on a logarithmic axis");
  }
}

#ifdef MIPNERF_HAVE_PLPLOT
bool has_driver(const char* name) {
  // PLplot fills the caller's arrays, `count` long on the way in, the drivers' count on the way out.
  const char* menu_storage[64];
  const char* name_storage[64];
  const char** menus = menu_storage;
  const char** names = name_storage;
  int count = 64;
  plgDevs(&menus, &names, &count);
  for (int i = 0; i < count; ++i) {
    if (std::string(names[i]) == name) return true;
  }
  return false;
}


void draw(const LinePlot& plot, const PlotRanges& r, const char* driver, const std::string& file) {
  plsdev(driver);
  plsfnam(file.c_str());
  plspage(0, 0, plot.width_px, plot.height_px, 0, 0);
  plscolbg(255, 255, 255);
  plscol0(kInk, 0, 0, 0);
  plscol0(kGrid, 220, 220, 220);
  for (int i = 0; i < kColourCount; ++i) plscol0(i + 1, kColours[i][0], kColours[i][1], kColours[i][2]);
  plinit();
  plcol0(kInk);
  auto x_of = [&](double x) { return plot.log_x ? std::log10(x) : x; };
  // The frame on the left two thirds of the page, the legend outside it on the right, so it never hides a curve.
  pladv(0);
  plvpor(0.09, 0.66, 0.11, 0.91);
  plwind(x_of(r.x_min), x_of(r.x_max), r.y_min, r.y_max);
  const char* x_axis = plot.log_x ? "gl" : "g";
  plcol0(kGrid);
  plbox(x_axis, 0, 0, "g", 0, 0);
  plcol0(kInk);
  plbox(plot.log_x ? "bcnstl" : "bcnst", 0, 0, "bcnstv", 0, 0);
  pllab(plot.x_label.c_str(), plot.y_label.c_str(), plot.title.c_str());
  const size_t n = plot.series.size();
  std::vector<PLINT> opts(n, PL_LEGEND_LINE | PL_LEGEND_SYMBOL), colours(n), styles(n), symbol_numbers(n, 3),
      text_colours(n, kInk);
  std::vector<PLFLT> widths(n, 1.5), symbol_scales(n, 0.35);
  std::vector<const char*> texts(n), symbols(n, "#(840)");  // a filled circle (Hershey 840)
  for (size_t s = 0; s < n; ++s) {
    const auto& series = plot.series[s];
    colours[s] = static_cast<PLINT>(s % kColourCount) + 1;
    styles[s] = static_cast<PLINT>((s / kColourCount) % 8) + 1;  // solid, then PLplot's dash patterns
    texts[s] = series.label.c_str();
    std::vector<PLFLT> x(series.x.size()), y(series.y.begin(), series.y.end());
    std::transform(series.x.begin(), series.x.end(), x.begin(), x_of);
    plcol0(colours[s]);
    pllsty(styles[s]);
    plwidth(widths[s]);
    plline(static_cast<PLINT>(x.size()), x.data(), y.data());
    plschr(0, 0.5);  // plstring's glyphs scale with the character height
    plstring(static_cast<PLINT>(x.size()), x.data(), y.data(), symbols[s]);
    plschr(0, 1.0);
  }
  pllsty(1);
  plwidth(1);
  PLFLT legend_width = 0, legend_height = 0;
  pllegend(&legend_width, &legend_height, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX,
           PL_POSITION_RIGHT | PL_POSITION_OUTSIDE | PL_POSITION_VIEWPORT, 0.02, 0.0, 0.04, 0, kInk, 1, 0, 0,
           static_cast<PLINT>(n), opts.data(), 0.8, 0.65, 1.6, 0.0, text_colours.data(), texts.data(), nullptr, nullptr,
           nullptr, nullptr, colours.data(), styles.data(), widths.data(), colours.data(), symbol_scales.data(),
           symbol_numbers.data(), symbols.data());
  plend();
}

#endif  // MIPNERF_HAVE_PLPLOT

}  // namespace

PlotRanges plot_ranges(const LinePlot& plot) {
  if (plot.series.empty()) throw Error("plot: no series to draw");
  double x_min = INFINITY, x_max = -INFINITY, y_min = INFINITY, y_max = -INFINITY;
  for (const auto& s : plot.series) {
    check_series(s, plot.log_x);
    x_min = std::min(x_min, *std::min_element(s.x.begin(), s.x.end()));
    x_max = std::max(x_max, *std::max_element(s.x.begin(), s.x.end()));
    y_min = std::min(y_min, *std::min_element(s.y.begin(), s.y.end()));
    y_max = std::max(y_max, *std::max_element(s.y.begin(), s.y.end()));
  }
  PlotRanges r;
  r.x_min = !plot.log_x && x_min >= 0 ? 0.0 : x_min;
  r.x_max = x_max;
  if (r.x_max <= r.x_min) r.x_max = plot.log_x ? r.x_min * 10 : r.x_min + 1;  // one x: a visible span
  const double pad = std::max(0.5, 0.05 * (y_max - y_min));
  r.y_min = y_min - pad;
  r.y_max = y_max + pad;
  return r;
}

void check_plot_path(const std::string& path) { driver_for(path); }

void write_line_plot(const std::string& path, const LinePlot& plot) {
  const char* driver = driver_for(path);
  const bool png = std::string(driver) == "pngcairo";
  const PlotRanges ranges = plot_ranges(plot);
#ifndef MIPNERF_HAVE_PLPLOT
  (void)png;
  (void)ranges;
  throw Error(path + ": this mipnerf-cl was built without PLplot, which draws plots: install the Debian packages "
                     "'libplplot-dev' and 'plplot-driver-cairo', then rebuild (scripts/build.sh)");
#else
  // PLplot keeps its state in globals: one plot at a time.
  static std::mutex plplot_mutex;
  std::lock_guard<std::mutex> lock(plplot_mutex);
  if (!has_driver(driver)) {
    throw Error(path + ": PLplot has no '" + driver + "' driver here; install the Debian package " +
                (png ? "'plplot-driver-cairo' (or write .svg)" : "'libplplot-dev'"));
  }
  write_atomically(path, [&](const std::string& temporary) { draw(plot, ranges, driver, temporary); });
#endif
}

}  // namespace mipnerf::io
