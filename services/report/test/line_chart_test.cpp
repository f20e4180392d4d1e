// Line charts for reports (line_chart.hpp): the CSV and gnuplot script written beside each chart,
// and the PNG, SVG and PDF gnuplot draws from them: data points at the pixels the fixed frame
// puts them, gaps, bands, a log axis; errors named.
#include "report/line_chart.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "file_test_util.hpp"

namespace pbnbv {
namespace {

using testing::file_text;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Throws E whose message contains `needle`.
template <typename E>
void expect_throw(const std::function<void()>& fn, const std::string& needle) {
  try {
    fn();
    ADD_FAILURE() << "no exception thrown";
  } catch (const E& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << "message '" << e.what() << "' lacks '" << needle << "'";
  }
}

// y = x at x = 0, 1, ..., 10, on fixed axes 0..10 (no margin: the frame maps them exactly).
LineChart diagonal() {
  LineChart c;
  c.title = "diagonal";
  c.x_label = "x";
  c.y_label = "y";
  c.x_min = c.y_min = 0;
  c.x_max = c.y_max = 10;
  ChartSeries s;
  s.label = "y = x";
  for (int i = 0; i <= 10; ++i) {
    s.x.push_back(i);
    s.y.push_back(i);
  }
  c.series.push_back(s);
  return c;
}

// The image pixel of data point (x, y) on axes [x0, x1] x [y0, y1] (y1 over y0, log10 when `log`):
// the data area is the fixed fraction of the image ChartFrame says.
cv::Point pixel(const cv::Mat& img, double x, double y, double x0, double x1, double y0, double y1, bool log = false) {
  const double fx = (x - x0) / (x1 - x0);
  const double fy = log ? (std::log10(y) - std::log10(y0)) / (std::log10(y1) - std::log10(y0)) : (y - y0) / (y1 - y0);
  const double sx = ChartFrame::kLeft + fx * (ChartFrame::kRight - ChartFrame::kLeft);
  const double sy = ChartFrame::kBottom + fy * (ChartFrame::kTop - ChartFrame::kBottom);
  return {static_cast<int>(std::lround(sx * (img.cols - 1))), static_cast<int>(std::lround((1 - sy) * (img.rows - 1)))};
}

// The colour "#rrggbb" as OpenCV's BGR.
cv::Vec3b bgr(const std::string& hex) {
  const int v = std::stoi(hex.substr(1), nullptr, 16);
  return cv::Vec3b(v & 0xff, (v >> 8) & 0xff, (v >> 16) & 0xff);
}

int distance(const cv::Vec3b& a, const cv::Vec3b& b) {
  int d = 0;
  for (int k = 0; k < 3; ++k) d = std::max(d, std::abs(int(a[k]) - int(b[k])));
  return d;
}

// The pixel nearest `colour` within `r` pixels of p, as its distance (0: exact).
int nearest_colour(const cv::Mat& img, cv::Point p, const cv::Vec3b& colour, int r = 2) {
  int best = 255;
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx) {
      const cv::Point q(p.x + dx, p.y + dy);
      if (q.x >= 0 && q.y >= 0 && q.x < img.cols && q.y < img.rows) best = std::min(best, distance(img.at<cv::Vec3b>(q), colour));
    }
  }
  return best;
}

class LineChartFile : public testing::TempDirTest {};

// The data beside the chart as CSV: one row per point, x, y, lo, hi, then the legend text quoted
// (a label with commas and quotes leaves the numbers in their columns); "nan" for a gap.
TEST(LineChart, CsvHasOneRowPerPointWithTheLabelLast) {
  LineChart c = diagonal();
  ChartSeries band;
  band.label = "mean \"A\", B";
  band.x = {1, 2};
  band.y = {0.5, kNaN};
  band.lo = {0.25, kNaN};
  band.hi = {0.75, kNaN};
  c.series.push_back(band);
  const std::string csv = line_chart_csv(c);
  EXPECT_EQ(csv.substr(0, csv.find('\n', csv.find('\n') + 1) + 1), "x,y,lo,hi,series\n0,0,,,\"y = x\"\n");
  EXPECT_NE(csv.find("10,10,,,\"y = x\"\n"), std::string::npos);
  EXPECT_NE(csv.find("1,0.5,0.25,0.75,\"mean \"\"A\"\", B\"\n2,nan,nan,nan,\"mean \"\"A\"\", B\"\n"), std::string::npos) << csv;
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 11 + 2);
}

// The script reads each series as its rows of the CSV (no label is parsed), bands under the lines,
// strings quoted for gnuplot, and writes the three files.
TEST(LineChart, TheScriptDrawsEachSeriesFromItsRows) {
  LineChart c = diagonal();
  c.title = "Bob's chart";
  ChartSeries band;
  band.label = "spread";
  band.x = {1, 2};
  band.y = {1, 2};
  band.lo = {0, 1};
  band.hi = {2, 3};
  c.series.push_back(band);
  const std::string gp = line_chart_gnuplot(c, "coverage");
  EXPECT_NE(gp.find("set title 'Bob''s chart' noenhanced"), std::string::npos) << gp;
  EXPECT_NE(gp.find("'coverage.csv' skip 1 every ::0::10 using ($1):($2) with linespoints"), std::string::npos) << gp;
  EXPECT_NE(gp.find("'coverage.csv' skip 1 every ::11::12 using ($1):($3):($4) with filledcurves"), std::string::npos) << gp;
  EXPECT_LT(gp.find("filledcurves"), gp.find("linespoints")) << "bands under the lines";
  EXPECT_NE(gp.find("title 'spread'"), std::string::npos);
  for (const char* out : {"set output 'coverage.png'", "set output 'coverage.svg'", "set output 'coverage.pdf'"}) {
    EXPECT_NE(gp.find(out), std::string::npos) << out;
  }
  EXPECT_NE(gp.find("set xrange [0:10]"), std::string::npos);
}

TEST_F(LineChartFile, WritesPngSvgAndPdfBesideItsDataAndScript) {
  LineChart c = diagonal();
  c.y_lines = {{9.5, "95 % target"}};
  const std::string p = path("chart.png");
  write_line_chart(c, p);
  const cv::Mat img = cv::imread(p, cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.size(), cv::Size(960, 600));
  const std::string svg = file_text(path("chart.svg"));
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  EXPECT_NE(svg.find("width=\"960\" height=\"600\""), std::string::npos);
  EXPECT_NE(svg.find(">diagonal</text>"), std::string::npos);
  EXPECT_EQ(file_text(path("chart.pdf")).substr(0, 5), "%PDF-");
  EXPECT_EQ(file_text(path("chart.csv")), line_chart_csv(c));
  EXPECT_EQ(file_text(path("chart.gp")), line_chart_gnuplot(c, "chart"));
  EXPECT_FALSE(std::filesystem::exists(path("chart.gnuplot.log")));

  write_line_chart(c, p, 640, 400);  // replaces the files
  EXPECT_EQ(cv::imread(p).size(), cv::Size(640, 400));
}

// Where the data are drawn, read back from the PNG: the series' colour at its points (the frame
// is fixed, the axes 0..10), nothing at a gap, a tint of it inside its band.
TEST_F(LineChartFile, PointsGapsAndBandsAreWhereTheFrameSays) {
  LineChart c = diagonal();
  ChartSeries flat;  // y = 2 with a gap at x = 5, and a band from 6 to 9
  flat.label = "flat";
  for (int i = 0; i <= 10; ++i) {
    flat.x.push_back(i);
    flat.y.push_back(i == 5 ? kNaN : 2.0);
    flat.lo.push_back(6.0);
    flat.hi.push_back(9.0);
  }
  c.series.push_back(flat);
  write_line_chart(c, path("chart.png"));
  const cv::Mat img = cv::imread(path("chart.png"), cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  const cv::Vec3b blue = bgr(chart_series_colour(0)), red = bgr(chart_series_colour(1));
  for (double x : {1.0, 3.0, 7.0}) {
    EXPECT_LE(nearest_colour(img, pixel(img, x, x, 0, 10, 0, 10), blue), 40) << "diagonal at " << x;
  }
  EXPECT_LE(nearest_colour(img, pixel(img, 2.5, 2, 0, 10, 0, 10), red), 40) << "the flat line between points";
  EXPECT_GT(nearest_colour(img, pixel(img, 5, 2, 0, 10, 0, 10), red, 1), 100) << "no line across the gap at x = 5";
  const cv::Vec3b tint = img.at<cv::Vec3b>(pixel(img, 2, 7.5, 0, 10, 0, 10));  // inside the band, away from lines
  EXPECT_LT(tint[1], 250) << "the band is not white";
  EXPECT_GT(tint[2], tint[0]) << "the band is tinted towards vermillion (more red than blue)";
  const cv::Vec3b outside = img.at<cv::Vec3b>(pixel(img, 2, 4.5, 0, 10, 0, 10));
  EXPECT_GE(std::min({outside[0], outside[1], outside[2]}), 220) << "outside the band: the white background or a grid line";
}

TEST_F(LineChartFile, ALogAxisSpacesDecadesEqually) {
  LineChart c;
  c.title = "time";
  c.log_y = true;
  c.x_min = 1;
  c.x_max = 4;
  c.y_min = 1;
  c.y_max = 1000;
  c.series.push_back({"ms", {1, 2, 3, 4}, {1, 10, 100, -1}});  // y <= 0: a gap on a log axis
  write_line_chart(c, path("time.png"));
  const cv::Mat img = cv::imread(path("time.png"), cv::IMREAD_COLOR);
  const cv::Vec3b blue = bgr(chart_series_colour(0));
  EXPECT_LE(nearest_colour(img, pixel(img, 2, 10, 1, 4, 1, 1000, true), blue), 40);
  EXPECT_LE(nearest_colour(img, pixel(img, 3, 100, 1, 4, 1, 1000, true), blue), 40);
  EXPECT_LE(nearest_colour(img, pixel(img, 2.5, std::sqrt(1000.0), 1, 4, 1, 1000, true), blue), 40)
      << "the segment from 10 to 100 passes their geometric mean half way";
}

TEST_F(LineChartFile, ErrorsAreNamed) {
  LineChart c = diagonal();
  c.series[0].y.pop_back();
  expect_throw<std::invalid_argument>([&] { check_line_chart(c); }, "series 0 'y = x' of line chart 'diagonal' has 11 x values but 10 y values");
  c = diagonal();
  c.series[0].lo = {1};
  expect_throw<std::invalid_argument>([&] { check_line_chart(c); }, "a band of 1 lo and 0 hi values");
  LineChart empty;
  empty.title = "empty chart";
  empty.series.push_back({"nan", {1, kNaN}, {kNaN, 3}});
  expect_throw<std::invalid_argument>([&] { write_line_chart(empty, path("e.png")); }, "line chart 'empty chart' has no finite point");
  LineChart log = diagonal();
  log.log_y = true;
  expect_throw<std::invalid_argument>([&] { check_line_chart(log); }, "y_min 0 is not positive on a log axis");
  LineChart reversed = diagonal();
  reversed.x_min = 5;
  reversed.x_max = 1;
  expect_throw<std::invalid_argument>([&] { check_line_chart(reversed); }, "x_min 5 is not below x_max 1");
  const std::string missing = path("no_such_folder/chart.png");
  expect_throw<std::runtime_error>([&] { write_line_chart(diagonal(), missing); }, "folder '" + path("no_such_folder") + "' does not exist");
  expect_throw<std::runtime_error>([&] { write_line_chart(diagonal(), path("chart.jpg")); }, "not a .png");
  // No gnuplot on the PATH: named, with where the data are.
  const std::string old_path = std::getenv("PATH");
  ::setenv("PATH", dir_.c_str(), 1);
  expect_throw<std::runtime_error>([&] { write_line_chart(diagonal(), path("chart.png")); }, "gnuplot is not installed");
  ::setenv("PATH", old_path.c_str(), 1);
}

}  // namespace
}  // namespace pbnbv
