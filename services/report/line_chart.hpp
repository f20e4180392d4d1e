#pragma once
// Line charts for benchmark reports (coverage against views, planning time, ...): axes with
// round tick values, a light grey grid, title and axis labels, a legend, horizontal reference
// lines. Drawn with OpenCV (core, imgproc, imgcodecs), written as PNG and SVG (the same
// primitives through report/canvas.hpp).
#include <opencv2/core.hpp>

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
  // in the series colour from lo to hi at each x (non-finite: a gap), under every line; the
  // axis range and the legend placement take it into account.
  std::vector<double> lo, hi;
};

struct LineChart {
  std::string title, x_label, y_label;
  std::vector<ChartSeries> series;
  double y_min = NAN, y_max = NAN;  // NaN: from the data (with a margin), nice round ticks
  double x_min = NAN, x_max = NAN;
  bool log_y = false;               // log10 axis; y <= 0 leaves a gap like a non-finite y
  bool integer_x = false;           // x ticks on integers only (view numbers 1..10)
  std::vector<std::pair<double, std::string>> y_lines;  // horizontal reference lines + label
};

// Draws the chart (CV_8UC3, white background, width_px x height_px). Series whose points are all
// non-finite are skipped. Series i has colour chart_series_colour(i); from the 8th on the colours
// repeat with dashed lines (dotted when the series is also `dashed`).
// Throws std::invalid_argument naming the series when its x and y differ in size, naming the
// chart (its title) when no series has a finite point (positive on a log axis), and when an axis
// range is empty or (log_y) not positive or the image is smaller than 240 x 160.
cv::Mat draw_line_chart(const LineChart& chart, int width_px = 960, int height_px = 600);
inline constexpr double kBandAlpha = 0.18;

// The same chart as an SVG document (width_px x height_px user units, one per image pixel).
std::string line_chart_svg(const LineChart& chart, int width_px = 960, int height_px = 600);

// The chart's data as CSV, one row per point: series (its legend text, quoted), x, y, lo, hi
// (empty when the series has no band); a non-finite value is written as "nan". The numbers are
// the plotted ones, to 9 significant digits, so that another tool can draw the chart again.
std::string line_chart_csv(const LineChart& chart);

// Draws and writes the chart as PNG, atomically (to path_png + ".tmp.png", then renamed), as
// SVG beside it (path_png with the extension ".svg") and its data as CSV (".csv"). Throws std::invalid_argument as draw_line_chart, and std::runtime_error naming the path when
// its folder does not exist or the file cannot be written.
void write_line_chart(const LineChart& chart, const std::string& path_png, int width_px = 960,
                      int height_px = 600);

// --- Layout (exposed for tests and for placing annotations) ---

struct ChartLayout {
  cv::Rect plot;                      // data area in image pixels; the frame is drawn around it
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;  // axis ranges (y values, not their log, when log_y)
  bool log_y = false;
  std::vector<double> x_ticks, y_ticks;   // labelled tick values (y: decades and 2, 5 when log_y)
  cv::Rect legend;                    // legend box (empty: no labelled series): inside the plot
                                      // where it covers no data, else right of the plot, else
                                      // below the x label (rows), else where it covers least
  // Image pixel (x right, y down) of a data point: (x0, y0) is the plot's bottom-left pixel,
  // (x1, y1) its top-right pixel (plot.x + plot.width - 1, plot.y). y must be > 0 when log_y.
  cv::Point to_pixel(double x, double y) const;
  cv::Point2d to_pixel_exact(double x, double y) const;  // without rounding
};

ChartLayout chart_layout(const LineChart& chart, int width_px = 960, int height_px = 600);

// Ticks at the multiples of the smallest step 1, 2 or 5 x 10^k that gives at most max_ticks of
// them in [lo, hi] (ends included), ascending. (0, 10, 6): 0 2 4 6 8 10.
std::vector<double> nice_ticks(double lo, double hi, int max_ticks);

// Decades 10^k in [lo, hi] (lo > 0), every decade or every 2nd, 3rd, 5th, 10th ... so that there
// are at most max_ticks. (0.8, 2000): 1 10 100 1000.
std::vector<double> log_ticks(double lo, double hi, int max_ticks = 10);

// Colour (BGR) of series i: Okabe-Ito's colour-blind-safe palette without yellow, 7 colours,
// then repeating.
cv::Vec3b chart_series_colour(size_t i);

}  // namespace pbnbv
