#pragma once
// Line charts for benchmark reports (coverage against views, planning time, ...), drawn by
// gnuplot (Debian's gnuplot-nox: PNG and PDF through cairo, SVG) from data written beside them:
// write_line_chart writes NAME.csv (the plotted numbers) and NAME.gp (the gnuplot script that
// draws NAME.csv) and runs gnuplot, which writes NAME.png, NAME.svg and NAME.pdf. A user redraws
// a chart with `gnuplot NAME.gp` in its folder, edits the script, or reads the CSV into any tool.
#include <cmath>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace pbnbv {

struct ChartSeries {
  std::string label;            // legend text (empty: not in the legend)
  std::vector<double> x, y;     // same size; a non-finite x or y leaves a gap in the line
  bool markers = true;          // draw a dot at each point
  bool dashed = false;          // e.g. a reference curve such as the paper's figures
  // Optional spread (e.g. min and max over objects): when both have x's size, a translucent band
  // in the series colour from lo to hi at each x (non-finite: a gap), under every line.
  std::vector<double> lo, hi;
};

struct LineChart {
  std::string title, x_label, y_label;
  std::vector<ChartSeries> series;
  double y_min = NAN, y_max = NAN;  // NaN: from the data
  double x_min = NAN, x_max = NAN;
  bool log_y = false;               // log10 axis; y <= 0 leaves a gap like a non-finite y
  bool integer_x = false;           // x ticks on integers only (view numbers 1..10)
  std::vector<std::pair<double, std::string>> y_lines;  // horizontal reference lines + label
};

// Where the data area lies in every image, as fractions of its width and height from the
// bottom-left corner (the legend is right of it): fixed, so that a data point's pixel is known.
struct ChartFrame {
  static constexpr double kLeft = 0.09, kRight = 0.76, kBottom = 0.11, kTop = 0.91;
};

// Series i's colour, "#rrggbb": Okabe and Ito's colour-blind-safe palette without yellow (7
// colours: blue, vermillion, bluish green, orange, reddish purple, sky blue, black), repeating
// with dashed lines from the 8th series on (dotted when the series is also `dashed`).
std::string chart_series_colour(std::size_t i);

// Throws std::invalid_argument naming the series when its x and y (or its band) differ in size,
// naming the chart (its title) when no series has a finite point (positive on a log axis), or an
// axis range is empty or (log_y) not positive.
void check_line_chart(const LineChart& chart);

// The chart's data as CSV, one row per point, series after series: x, y, lo, hi (empty when the
// series has no band), series (its legend text, quoted); a non-finite value is written "nan".
// The numbers are the plotted ones, to 9 significant digits. The label comes last so that a
// label holding commas or quotes leaves the numeric columns where they are.
std::string line_chart_csv(const LineChart& chart);

// The gnuplot script that draws `stem`.csv (line_chart_csv of the same chart, in the script's
// folder) into `stem`.png and `stem`.svg (width_px x height_px) and `stem`.pdf (the same shape,
// 10 inches wide). Each series is a range of the CSV's rows (`every`), so no label is parsed.
std::string line_chart_gnuplot(const LineChart& chart, const std::string& stem, int width_px = 960,
                               int height_px = 600);

// Writes the chart's CSV and script beside path_png (same name, .csv and .gp) and runs gnuplot
// there (at most 60 s), which writes path_png, the .svg and the .pdf. Throws as check_line_chart,
// and std::runtime_error naming the path when its folder does not exist or a file cannot be
// written, and naming gnuplot and the end of what it said when it fails, is missing or times out.
void write_line_chart(const LineChart& chart, const std::string& path_png, int width_px = 960,
                      int height_px = 600);

}  // namespace pbnbv
