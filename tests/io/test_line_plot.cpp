// io::write_line_plot (PLplot): the axes' ranges, refusals naming what is wrong, and the pictures themselves: an SVG
// document, and a PNG of the page's size whose pixels show each curve's colour exactly when that curve is drawn.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.hpp"
#include "io/file.hpp"
#include "io/line_plot.hpp"
#include "io/png.hpp"
#include "support/temp_scene.hpp"

using namespace mipnerf;
namespace fs = std::filesystem;

namespace {

io::LinePlot two_curves() {
  io::LinePlot plot;
  plot.title = "test";
  plot.x_label = "seconds";
  plot.y_label = "PSNR";
  plot.series = {{"first", {10, 20, 40}, {14, 18, 21}}, {"second", {5, 30}, {12, 16}}};
  return plot;
}

// Pixels within 8 levels of an 8-bit colour (anti-aliased lines keep their colour at their core).
size_t pixels_of(const io::PngImage& image, int r, int g, int b) {
  size_t count = 0;
  for (size_t i = 0; i < size_t(image.width) * image.height; ++i) {
    const float* p = &image.rgba[4 * i];
    if (std::abs(p[0] * 255 - r) <= 8 && std::abs(p[1] * 255 - g) <= 8 && std::abs(p[2] * 255 - b) <= 8) ++count;
  }
  return count;
}

}  // namespace

TEST_CASE("line plot: ranges start x at 0 on a linear axis, pad y, and keep a single point visible") {
  const auto r = io::plot_ranges(two_curves());
  CHECK(r.x_min == 0.0);
  CHECK(r.x_max == 40.0);
  CHECK(r.y_min == doctest::Approx(12 - 0.5));  // span 9: 5 % is 0.45, below the 0.5 floor
  CHECK(r.y_max == doctest::Approx(21 + 0.5));
  io::LinePlot wide = two_curves();
  wide.series[0].y = {0, 100, 50};
  const auto w = io::plot_ranges(wide);
  CHECK(w.y_min == doctest::Approx(-5.0));  // 5 % of a span of 100
  CHECK(w.y_max == doctest::Approx(105.0));
  io::LinePlot log = two_curves();
  log.log_x = true;
  CHECK(io::plot_ranges(log).x_min == 5.0);  // a log axis starts at the smallest x
  io::LinePlot one;
  one.series = {{"one", {0}, {10}}};
  const auto o = io::plot_ranges(one);
  CHECK(o.x_max > o.x_min);
  CHECK(o.y_max > o.y_min);
}

TEST_CASE(
    "line plot: empty plots, unequal series, non-finite values, x <= 0 on a log axis and other formats are refused") {
  io::LinePlot empty;
  CHECK_THROWS_WITH_AS(io::plot_ranges(empty), "plot: no series to draw", Error);
  io::LinePlot unequal = two_curves();
  unequal.series[1].y.pop_back();
  CHECK_THROWS_WITH_AS(io::plot_ranges(unequal), doctest::Contains("series 'second': 2 x and 1 y values"), Error);
  io::LinePlot nan = two_curves();
  nan.series[0].y[1] = NAN;
  CHECK_THROWS_WITH_AS(io::plot_ranges(nan), doctest::Contains("series 'first': point 1 is not finite"), Error);
  io::LinePlot log = two_curves();
  log.log_x = true;
  log.series[1].x[0] = 0;
  CHECK_THROWS_WITH_AS(io::plot_ranges(log), doctest::Contains("series 'second': x = 0"), Error);
  const auto dir = test::fresh_temp_dir("plot-refusals");
  fs::create_directories(dir);
  CHECK_THROWS_WITH_AS(io::write_line_plot((dir / "p.pdf").string(), two_curves()),
                       doctest::Contains("p.pdf: a plot is written as .svg or .png; '.pdf' is neither"), Error);
  CHECK_NOTHROW(io::check_plot_path("x/P.SVG"));
  CHECK_THROWS_AS(io::check_plot_path("x/p"), Error);
  CHECK(fs::is_empty(dir));  // nothing written by a refusal
}

TEST_CASE("line plot: an SVG document, and a PNG of the page's size showing each drawn curve's colour") {
  const auto dir = test::fresh_temp_dir("plot-pictures");
  fs::create_directories(dir);
  const std::string svg = (dir / "curves.svg").string();
  io::write_line_plot(svg, two_curves());
  const std::string text = io::read_file_text(svg);
  CHECK(text.rfind("<?xml", 0) == 0);
  CHECK(text.find("<svg") != std::string::npos);
  CHECK(text.find("</svg>") != std::string::npos);

  const std::string png = (dir / "curves.png").string();
  io::write_line_plot(png, two_curves());
  const io::PngImage both = io::read_png(png);
  CHECK(both.width == 1000);
  CHECK(both.height == 560);
  // The first two colours of the palette: (31, 119, 180) and (255, 127, 14).
  CHECK(pixels_of(both, 31, 119, 180) > 100);
  CHECK(pixels_of(both, 255, 127, 14) > 100);
  io::LinePlot first_only = two_curves();
  first_only.series.pop_back();
  io::write_line_plot(png, first_only);
  const io::PngImage one = io::read_png(png);
  CHECK(pixels_of(one, 31, 119, 180) > 100);
  CHECK(pixels_of(one, 255, 127, 14) == 0);
  // Only the two pictures: the writes went through temporaries that were renamed.
  size_t files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) files += entry.is_regular_file() ? 1 : 0;
  CHECK(files == 2);
}
