// Line charts for reports (line_chart.hpp): tick values, pixel mapping, drawn colours, legend
// placement, PNG output, errors.
#include "report/line_chart.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "file_test_util.hpp"

namespace pbnbv {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Throws E whose message contains `needle`.
template <typename E>
void expect_throw(const std::function<void()>& fn, const std::string& needle) {
  try {
    fn();
    ADD_FAILURE() << "no exception thrown";
  } catch (const E& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos)
        << "message '" << e.what() << "' lacks '" << needle << "'";
  }
}

// y = x at x = 0, 1, ..., 10.
LineChart diagonal() {
  LineChart c;
  c.title = "diagonal";
  c.x_label = "x";
  c.y_label = "y";
  ChartSeries s;
  s.label = "y = x";
  for (int i = 0; i <= 10; ++i) {
    s.x.push_back(i);
    s.y.push_back(i);
  }
  c.series.push_back(s);
  return c;
}

cv::Vec3b at(const cv::Mat& img, const cv::Point& p) { return img.at<cv::Vec3b>(p.y, p.x); }

int distance(const cv::Vec3b& a, const cv::Vec3b& b) {
  int d = 0;
  for (int k = 0; k < 3; ++k) d = std::max(d, std::abs(int(a[k]) - int(b[k])));
  return d;
}

// Ticks are ascending multiples of one step 1, 2 or 5 x 10^k inside [lo, hi].
void expect_nice(const std::vector<double>& t, double lo, double hi) {
  ASSERT_GE(t.size(), 2u);
  const double step = t[1] - t[0];
  const double mantissa = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
  EXPECT_TRUE(std::abs(mantissa - 1) < 1e-9 || std::abs(mantissa - 2) < 1e-9 ||
              std::abs(mantissa - 5) < 1e-9)
      << "step " << step;
  for (size_t i = 0; i < t.size(); ++i) {
    EXPECT_GE(t[i], lo);
    EXPECT_LE(t[i], hi);
    EXPECT_NEAR(t[i] / step, std::round(t[i] / step), 1e-9) << t[i];
    if (i > 0) {
      EXPECT_NEAR(t[i] - t[i - 1], step, 1e-9 * step);
    }
  }
}

TEST(NiceTicks, OneTwoFiveSteps) {
  // (0, 10), at most 6: step 1 gives 11 ticks, step 2 gives 6.
  EXPECT_EQ(nice_ticks(0, 10, 6), (std::vector<double>{0, 2, 4, 6, 8, 10}));
  // (0, 100), at most 6: step 10 gives 11, step 20 gives 6.
  EXPECT_EQ(nice_ticks(0, 100, 6), (std::vector<double>{0, 20, 40, 60, 80, 100}));
  // (0, 1), at most 5: step 0.1 gives 11, 0.2 gives 6, 0.5 gives 3.
  EXPECT_EQ(nice_ticks(0, 1, 5), (std::vector<double>{0, 0.5, 1}));
  // Padded coverage axis (27.2, 102.8), at most 8: step 10 gives 30..100, 8 ticks.
  EXPECT_EQ(nice_ticks(27.2, 102.8, 8), (std::vector<double>{30, 40, 50, 60, 70, 80, 90, 100}));
  // Decimal steps give the doubles of the decimal literals, not 3 x 0.1.
  EXPECT_EQ(nice_ticks(0.1, 0.35, 3), (std::vector<double>{0.1, 0.2, 0.3}));
  // Negative range, (-7, 3), at most 4: step 2 gives 5, step 5 gives -5, 0.
  EXPECT_EQ(nice_ticks(-7, 3, 4), (std::vector<double>{-5, 0}));
}

TEST(NiceTicks, LogDecades) {
  EXPECT_EQ(log_ticks(0.8, 2000), (std::vector<double>{1, 10, 100, 1000}));
  // 10^-3 .. 10^6 is 10 decades; at most 4: every 3rd decade (-3, 0, 3, 6).
  EXPECT_EQ(log_ticks(0.001, 1e6, 4), (std::vector<double>{0.001, 1, 1000, 1e6}));
  EXPECT_TRUE(log_ticks(-1, 10).empty());
}

TEST(LineChart, LayoutMapsAxisRangeToPlotCorners) {
  const LineChart c = diagonal();
  const ChartLayout l = chart_layout(c, 960, 600);
  const cv::Rect image(0, 0, 960, 600);
  EXPECT_EQ(l.plot & image, l.plot);
  EXPECT_GT(l.plot.width, 700);
  EXPECT_GT(l.plot.height, 400);
  // Range from the data with a margin on each side.
  EXPECT_LT(l.x0, 0.0);
  EXPECT_GT(l.x1, 10.0);
  EXPECT_LT(l.y0, 0.0);
  EXPECT_GT(l.y1, 10.0);
  EXPECT_EQ(l.to_pixel(l.x0, l.y0), cv::Point(l.plot.x, l.plot.y + l.plot.height - 1));
  EXPECT_EQ(l.to_pixel(l.x1, l.y1), cv::Point(l.plot.x + l.plot.width - 1, l.plot.y));
  EXPECT_EQ(l.to_pixel(l.x0, l.y1), cv::Point(l.plot.x, l.plot.y));
  EXPECT_TRUE(l.plot.contains(l.to_pixel(0, 0)));
  EXPECT_TRUE(l.plot.contains(l.to_pixel(10, 10)));
  // Linear: the middle of the data maps half-way between the endpoints.
  const cv::Point2d a = l.to_pixel_exact(0, 0), b = l.to_pixel_exact(10, 10),
                    m = l.to_pixel_exact(5, 5);
  EXPECT_NEAR(m.x, (a.x + b.x) / 2, 1e-9);
  EXPECT_NEAR(m.y, (a.y + b.y) / 2, 1e-9);
  expect_nice(l.x_ticks, l.x0, l.x1);
  expect_nice(l.y_ticks, l.y0, l.y1);
  EXPECT_EQ(l.x_ticks.front(), 0.0);
  EXPECT_EQ(l.x_ticks.back(), 10.0);
}

TEST(LineChart, FixedRangeAndIntegerTicks) {
  LineChart c = diagonal();
  c.y_min = 0;
  c.y_max = 100;
  c.x_min = 0.5;
  c.x_max = 10.5;
  c.integer_x = true;
  const ChartLayout l = chart_layout(c, 480, 300);
  EXPECT_EQ(l.y0, 0.0);
  EXPECT_EQ(l.y1, 100.0);
  EXPECT_EQ(l.x0, 0.5);
  EXPECT_EQ(l.x1, 10.5);
  expect_nice(l.x_ticks, 0.5, 10.5);
  for (double t : l.x_ticks) EXPECT_EQ(t, std::round(t));
  // A range of 0.3 still gets integer ticks only (here the single integer 2).
  c.x_min = 1.8;
  c.x_max = 2.1;
  const ChartLayout k = chart_layout(c, 480, 300);
  EXPECT_EQ(k.x_ticks, (std::vector<double>{2}));
}

TEST(LineChart, LogAxis) {
  LineChart c;
  c.title = "planning time";
  c.log_y = true;
  c.series.push_back({"time", {1, 2, 3, 4}, {5, 100, 3000, -1}});  // -1: skipped
  const ChartLayout l = chart_layout(c, 960, 600);
  EXPECT_TRUE(l.log_y);
  EXPECT_LT(l.y0, 5.0);
  EXPECT_GT(l.y1, 3000.0);
  EXPECT_LT(l.y1, 10000.0);
  for (double d : {10.0, 100.0, 1000.0}) {
    EXPECT_NE(std::find(l.y_ticks.begin(), l.y_ticks.end(), d), l.y_ticks.end()) << d;
  }
  // Decades equally far apart; 2 x and 5 x in between at log10(2) and log10(5) of a decade.
  const double p10 = l.to_pixel_exact(1, 10).y, p100 = l.to_pixel_exact(1, 100).y,
               p1000 = l.to_pixel_exact(1, 1000).y, p20 = l.to_pixel_exact(1, 20).y;
  EXPECT_NEAR(p10 - p100, p100 - p1000, 1e-6);
  EXPECT_GT(p10 - p100, 100.0);
  EXPECT_NEAR((p10 - p20) / (p10 - p100), std::log10(2.0), 1e-9);
  // Room for the 2 and 5 labels at > 100 px per decade.
  EXPECT_NE(std::find(l.y_ticks.begin(), l.y_ticks.end(), 20.0), l.y_ticks.end());
  EXPECT_NE(std::find(l.y_ticks.begin(), l.y_ticks.end(), 500.0), l.y_ticks.end());
  EXPECT_EQ(l.to_pixel(1, l.y0).y, l.plot.y + l.plot.height - 1);
  EXPECT_EQ(l.to_pixel(1, l.y1).y, l.plot.y);
  // The point at y = 100 is drawn; nothing for y = -1 (no throw either).
  const cv::Mat img = draw_line_chart(c, 960, 600);
  EXPECT_LE(distance(at(img, l.to_pixel(2, 100)), chart_series_colour(0)), 2);
}

TEST(LineChart, DataPointsHaveTheSeriesColour) {
  const LineChart c = diagonal();
  const cv::Mat img = draw_line_chart(c, 960, 600);
  ASSERT_EQ(img.type(), CV_8UC3);
  ASSERT_EQ(img.size(), cv::Size(960, 600));
  const ChartLayout l = chart_layout(c, 960, 600);
  for (int i = 0; i <= 10; ++i) {
    EXPECT_LE(distance(at(img, l.to_pixel(i, i)), chart_series_colour(0)), 2) << "point " << i;
  }
  // Far from the line: background or grid, never the series colour.
  EXPECT_GT(distance(at(img, l.to_pixel(8, 2)), chart_series_colour(0)), 100);
  // The image corner is white background.
  EXPECT_EQ(at(img, {0, 0}), cv::Vec3b(255, 255, 255));
}

TEST(LineChart, NonFiniteValueLeavesAGap) {
  LineChart c;
  ChartSeries s;
  s.x = {0, 1, 2, 3, 4};
  s.y = {0, 1, kNaN, 3, 4};
  s.markers = false;
  c.series = {s};
  const cv::Mat img = draw_line_chart(c, 960, 600);
  const ChartLayout l = chart_layout(c, 960, 600);
  // On the segment 0-1 (drawn) and where 1-3 would cross x = 2 (not drawn).
  EXPECT_LE(distance(at(img, l.to_pixel(0.5, 0.5)), chart_series_colour(0)), 60);
  EXPECT_LE(distance(at(img, l.to_pixel(3.5, 3.5)), chart_series_colour(0)), 60);
  EXPECT_GT(distance(at(img, l.to_pixel(2, 2)), chart_series_colour(0)), 100);
}

TEST(LineChart, AllNonFiniteSeriesIsSkipped) {
  const LineChart c = diagonal();
  LineChart d = c;
  d.series.push_back({"nothing", {1, 2}, {kNaN, kNaN}});
  const cv::Mat a = draw_line_chart(c, 640, 400), b = draw_line_chart(d, 640, 400);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);  // not drawn, not in the legend
}

TEST(LineChart, LegendAvoidsDataOrGoesOutside) {
  // One diagonal: the legend fits in an empty corner inside the plot.
  LineChart c = diagonal();
  ChartLayout l = chart_layout(c, 960, 600);
  ASSERT_FALSE(l.legend.empty());
  EXPECT_EQ(l.legend & l.plot, l.legend);
  for (int i = 0; i <= 10; ++i) EXPECT_FALSE(l.legend.contains(l.to_pixel(i, i))) << i;

  // Eleven horizontal lines y = 0..10 across the whole plot: no room inside.
  LineChart full;
  for (int k = 0; k <= 10; ++k) {
    full.series.push_back({"level " + std::to_string(k), {0, 10}, {double(k), double(k)}});
  }
  l = chart_layout(full, 960, 600);
  ASSERT_FALSE(l.legend.empty());
  EXPECT_GE(l.legend.x, l.plot.x + l.plot.width);
  EXPECT_LE(l.legend.x + l.legend.width, 960);
  EXPECT_LE(l.legend.y + l.legend.height, 600);

  // Small image, both corners and sides taken, too narrow for a column on the right: the legend
  // goes below the x label, within the image.
  LineChart two;
  two.x_label = "view number";
  two.series = {{"first method", {1, 2, 3, 4, 5, 6}, {1, 9, 1, 9, 1, 9}},
                {"second, longer label of a method", {1, 6}, {5, 5}}};
  l = chart_layout(two, 480, 300);
  ASSERT_FALSE(l.legend.empty());
  EXPECT_GE(l.legend.y, l.plot.y + l.plot.height);
  EXPECT_EQ(l.legend & cv::Rect(0, 0, 480, 300), l.legend);

  // No labelled series: no legend.
  c.series[0].label.clear();
  EXPECT_TRUE(chart_layout(c, 960, 600).legend.empty());
}

// A band from lo to hi in the series colour at kBandAlpha over white: inside it the blend, outside
// white; the axis range grows to hold it; a band of the wrong size throws naming the series.
TEST(LineChart, BandShowsTheSpread) {
  LineChart c = diagonal();
  c.y_min = -5;
  c.y_max = 15;
  ChartSeries& s = c.series[0];
  for (int i = 0; i <= 10; ++i) {
    s.lo.push_back(i - 3.0);
    s.hi.push_back(i + 3.0);
  }
  const ChartLayout l = chart_layout(c);
  const cv::Mat img = draw_line_chart(c);
  const cv::Vec3b col = chart_series_colour(0);
  cv::Vec3b blend;
  for (int k = 0; k < 3; ++k) blend[k] = cv::saturate_cast<uchar>(kBandAlpha * col[k] + (1 - kBandAlpha) * 255);
  // (5, 7): 2 above the line, inside the band; (5, 9.5): outside it (grid lines at 10, not 9.5).
  EXPECT_LE(distance(at(img, l.to_pixel(5.5, 7.5)), blend), 3);
  EXPECT_EQ(at(img, l.to_pixel(5.5, 9.7)), cv::Vec3b(255, 255, 255));
  EXPECT_LE(distance(at(img, l.to_pixel(5.5, 3.5)), blend), 3);
  // Without fixed y limits, the range holds the band (lo -3 at x = 0, hi 13 at x = 10).
  LineChart d = c;
  d.y_min = d.y_max = kNaN;
  const ChartLayout m = chart_layout(d);
  EXPECT_LE(m.y0, -3.0);
  EXPECT_GE(m.y1, 13.0);
  LineChart bad = diagonal();
  bad.series[0].lo = {1, 2};
  bad.series[0].hi = {1, 2};
  expect_throw<std::invalid_argument>([&] { draw_line_chart(bad); }, "series 0 'y = x'");
}

TEST(LineChart, PaletteColoursAreDistinct) {
  for (size_t i = 0; i < 7; ++i) {
    for (size_t j = i + 1; j < 7; ++j) {
      EXPECT_GT(distance(chart_series_colour(i), chart_series_colour(j)), 40) << i << " " << j;
    }
    EXPECT_EQ(chart_series_colour(i + 7), chart_series_colour(i));  // repeats (dashed)
  }
}

TEST(LineChart, Errors) {
  LineChart c = diagonal();
  c.series.push_back({"short one", {1, 2, 3}, {1, 2}});
  expect_throw<std::invalid_argument>([&] { draw_line_chart(c); }, "short one");
  expect_throw<std::invalid_argument>([&] { write_line_chart(c, "/tmp/never.png"); },
                                      "short one");

  LineChart empty;
  empty.title = "empty chart";
  empty.series.push_back({"nan", {1, 2}, {kNaN, 3}});
  empty.series[0].x[1] = kNaN;
  expect_throw<std::invalid_argument>([&] { draw_line_chart(empty); }, "empty chart");
  expect_throw<std::invalid_argument>([&] { write_line_chart(empty, "/tmp/never.png"); },
                                      "empty chart");

  LineChart log = diagonal();  // y > 0 only at x = 1..10: fine; y_min = 0 is not
  log.log_y = true;
  EXPECT_NO_THROW(chart_layout(log, 960, 600));
  log.y_min = 0;
  expect_throw<std::invalid_argument>([&] { chart_layout(log, 960, 600); }, "y_min");

  LineChart reversed = diagonal();
  reversed.x_min = 5;
  reversed.x_max = 1;
  expect_throw<std::invalid_argument>([&] { chart_layout(reversed, 960, 600); }, "x_min");
}

class LineChartFile : public testing::TempDirTest {};

TEST_F(LineChartFile, WritesPngOfTheRequestedSize) {
  LineChart c = diagonal();
  c.y_lines = {{9.5, "95 % target"}};
  const std::string p = path("chart.png");
  write_line_chart(c, p);
  const cv::Mat img = cv::imread(p, cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.size(), cv::Size(960, 600));
  EXPECT_EQ(cv::norm(img, draw_line_chart(c), cv::NORM_INF), 0.0);  // PNG is lossless
  EXPECT_FALSE(std::filesystem::exists(p + ".tmp.png"));

  write_line_chart(c, p, 640, 400);  // replaces the file
  EXPECT_EQ(cv::imread(p).size(), cv::Size(640, 400));
}

std::string read_all(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The data beside the PNG as CSV: one row per point with the legend text quoted, the band's lo
// and hi when there is one, "nan" for a gap.
TEST_F(LineChartFile, WritesTheDataBesideThePngAsCsv) {
  LineChart c = diagonal();
  ChartSeries band;
  band.label = "mean \"A\"";
  band.x = {1, 2};
  band.y = {0.5, NAN};
  band.lo = {0.25, NAN};
  band.hi = {0.75, NAN};
  c.series.push_back(band);
  write_line_chart(c, path("chart.png"), 640, 400);
  const std::string csv = read_all(path("chart.csv"));
  EXPECT_EQ(csv, line_chart_csv(c));
  EXPECT_EQ(csv.substr(0, csv.find('\n', csv.find('\n') + 1) + 1), "series,x,y,lo,hi\n\"y = x\",0,0,,\n");
  EXPECT_NE(csv.find("\"y = x\",10,10,,\n"), std::string::npos);
  EXPECT_NE(csv.find("\"mean \"\"A\"\"\",1,0.5,0.25,0.75\n\"mean \"\"A\"\"\",2,nan,nan,nan\n"), std::string::npos) << csv;
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 11 + 2);
}

// The SVG beside the PNG draws the same primitives: the same size, the title, and each data
// point's marker at the PNG's pixel centre (pixel i covers [i, i+1) in SVG units).
TEST_F(LineChartFile, WritesSvgBesideThePngWithTheSamePrimitives) {
  const LineChart c = diagonal();
  const std::string p = path("chart.png");
  write_line_chart(c, p, 640, 400);
  const std::string svg = read_all(path("chart.svg"));
  ASSERT_FALSE(svg.empty());
  EXPECT_EQ(svg, line_chart_svg(c, 640, 400));
  EXPECT_NE(svg.find("<svg "), std::string::npos);
  EXPECT_NE(svg.find("width=\"640\" height=\"400\""), std::string::npos);
  EXPECT_NE(svg.find(">diagonal</text>"), std::string::npos);
  EXPECT_NE(svg.find(">y = x</text>"), std::string::npos);  // legend
  const ChartLayout l = chart_layout(c, 640, 400);
  const cv::Vec3b col = chart_series_colour(0);
  char fill[8];
  std::snprintf(fill, sizeof(fill), "#%02x%02x%02x", col[2], col[1], col[0]);
  for (int i = 0; i <= 10; ++i) {
    const cv::Point2d q = l.to_pixel_exact(i, i);
    char circle[160];
    std::snprintf(circle, sizeof(circle), "<circle clip-path=\"url(#c0)\" cx=\"%.2f\" cy=\"%.2f\" r=\"3.50\" fill=\"%s\"/>",
                  q.x + 0.5, q.y + 0.5, fill);
    EXPECT_NE(svg.find(circle), std::string::npos) << "no marker " << circle;
  }
  // Escaped text.
  LineChart d = diagonal();
  d.title = "a < b & c";
  EXPECT_NE(line_chart_svg(d).find(">a &lt; b &amp; c</text>"), std::string::npos);
}

TEST_F(LineChartFile, UnwritablePathThrowsNamingIt) {
  const LineChart c = diagonal();
  const std::string missing = path("no_such_folder/chart.png");
  expect_throw<std::runtime_error>([&] { write_line_chart(c, missing); }, missing);
  // The path is a folder: the rename onto it fails, and no temporary file is left.
  const std::string folder = path("a_folder");
  std::filesystem::create_directories(folder);
  expect_throw<std::runtime_error>([&] { write_line_chart(c, folder); }, folder);
  EXPECT_FALSE(std::filesystem::exists(folder + ".tmp.png"));
  EXPECT_TRUE(std::filesystem::is_directory(folder));
}

}  // namespace
}  // namespace pbnbv
