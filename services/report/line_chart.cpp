#include "report/line_chart.hpp"

#include "report/canvas.hpp"

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <system_error>
#include <tuple>

namespace pbnbv {
namespace {

using drawing::Canvas;
using drawing::Svg;
using drawing::svg_path_beside;
using drawing::write_text_file;
using drawing::kBlack;
using drawing::kFont;
using drawing::kFrame;
using drawing::kSubText;
using drawing::kText;
using drawing::scalar;
using drawing::text_size;


constexpr int kMinWidth = 240;
constexpr int kMinHeight = 160;

// Image coordinates: pixel centres at integers.
constexpr double kPixelCentre = 0.0;

// Text scales (Hershey simplex) and layout (pixels).
constexpr double kTitleScale = 0.7;
constexpr double kTitleScaleMin = 0.45;
constexpr double kLabelScale = 0.55;
constexpr double kLabelScaleMin = 0.4;
constexpr double kTickScale = 0.45;
constexpr double kLegendScale = 0.48;
constexpr double kRefScale = 0.45;
constexpr int kEdge = 12;        // image border kept free of text
constexpr int kTickLen = 5;      // tick marks outside the frame
constexpr int kTickGap = 4;      // tick mark to tick text
constexpr int kLabelGap = 12;    // tick text to axis label
constexpr int kSwatch = 30;      // legend line sample length
constexpr int kLegendPad = 8;
constexpr int kLegendInset = 10;  // legend inside the plot: distance from the frame
constexpr int kLegendGap = 16;    // legend outside the plot: distance from the frame
constexpr double kMarkerRadius = 3.5;
constexpr int kLineThickness = 2;

const cv::Scalar kBackground(255, 255, 255);
const cv::Scalar kGrid(228, 228, 228);
const cv::Scalar kMinorGrid(243, 243, 243);
const cv::Scalar kRefLine(110, 110, 110);

// Line patterns: on/off lengths in pixels; solid has none.
enum class Pattern { kSolid, kDashed, kDotted };
constexpr int kPaletteSize = 7;

std::string chart_name(const LineChart& c) {
  return c.title.empty() ? std::string("line chart (untitled)") : "line chart '" + c.title + "'";
}

std::string series_name(const LineChart& c, size_t i) {
  std::string s = "series " + std::to_string(i);
  if (!c.series[i].label.empty()) s += " '" + c.series[i].label + "'";
  return s + " of " + chart_name(c);
}

std::string number(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%g", v);
  return buf;
}

double pow10i(int k) { return k >= 0 ? std::pow(10.0, k) : 1.0 / std::pow(10.0, -k); }

// Tick text for v on an axis with tick spacing `step` (decimals as the step needs).
std::string tick_text(double v, double step) {
  const double a = std::abs(v);
  if (a < std::abs(step) * 1e-6) return "0";
  char buf[64];
  if (a >= 1e6 || a < 1e-4) {
    const int e = static_cast<int>(std::floor(std::log10(a) + 1e-9));
    std::snprintf(buf, sizeof(buf), "%.3ge%d", v / pow10i(e), e);
    return buf;
  }
  const int decimals =
      std::clamp(static_cast<int>(-std::floor(std::log10(std::abs(step)) + 1e-9)), 0, 10);
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, v);
  return buf;
}

// Shortens s with "..." until it is at most max_w pixels wide.
std::string ellipsize(std::string s, double scale, int thickness, int max_w) {
  if (text_size(s, scale, thickness).width <= max_w) return s;
  while (!s.empty() && text_size(s + "...", scale, thickness).width > max_w) s.pop_back();
  return s + "...";
}

// A text line that fits max_w: scale shrunk from hi down to lo, then shortened.
struct FittedText {
  std::string text;
  double scale = 0;
  int thickness = 1;
  cv::Size size;  // without the baseline
  int baseline = 0;
};

FittedText fit_text(const std::string& s, int max_w, double hi, double lo, int thickness) {
  FittedText f;
  f.thickness = thickness;
  f.scale = hi;
  while (f.scale > lo && text_size(s, f.scale, thickness).width > max_w) f.scale -= 0.05;
  f.scale = std::max(f.scale, lo);
  f.text = ellipsize(s, f.scale, thickness, max_w);
  f.size = text_size(f.text, f.scale, thickness, &f.baseline);
  return f;
}

bool usable(double x, double y, bool log_y) {
  return std::isfinite(x) && std::isfinite(y) && (!log_y || y > 0);
}

bool has_usable_point(const ChartSeries& s, bool log_y) {
  for (size_t k = 0; k < s.x.size(); ++k) {
    if (usable(s.x[k], s.y[k], log_y)) return true;
  }
  return false;
}

Pattern series_pattern(const ChartSeries& s, size_t i) {
  const int p = (static_cast<int>(i / kPaletteSize) + (s.dashed ? 1 : 0)) % 3;
  return p == 0 ? Pattern::kSolid : p == 1 ? Pattern::kDashed : Pattern::kDotted;
}

void validate(const LineChart& c, int w, int h) {
  if (w < kMinWidth || h < kMinHeight) {
    throw std::invalid_argument(chart_name(c) + ": image size " + std::to_string(w) + " x " +
                                std::to_string(h) + " is smaller than " +
                                std::to_string(kMinWidth) + " x " + std::to_string(kMinHeight));
  }
  for (size_t i = 0; i < c.series.size(); ++i) {
    const ChartSeries& s = c.series[i];
    if (s.x.size() != s.y.size()) {
      throw std::invalid_argument(series_name(c, i) + " has " + std::to_string(s.x.size()) +
                                  " x values but " + std::to_string(s.y.size()) + " y values");
    }
    if ((!s.lo.empty() || !s.hi.empty()) && (s.lo.size() != s.x.size() || s.hi.size() != s.x.size())) {
      throw std::invalid_argument(series_name(c, i) + " has " + std::to_string(s.x.size()) + " x values but a band of " +
                                  std::to_string(s.lo.size()) + " lo and " + std::to_string(s.hi.size()) + " hi values");
    }
  }
  auto check_pair = [&](double lo, double hi, const char* lo_name, const char* hi_name) {
    if (std::isfinite(lo) && std::isfinite(hi) && !(lo < hi)) {
      throw std::invalid_argument(chart_name(c) + ": " + lo_name + " " + number(lo) +
                                  " is not below " + hi_name + " " + number(hi));
    }
  };
  check_pair(c.x_min, c.x_max, "x_min", "x_max");
  check_pair(c.y_min, c.y_max, "y_min", "y_max");
  if (c.log_y) {
    using Bound = std::pair<double, const char*>;
    for (const auto& [v, name] : {Bound{c.y_min, "y_min"}, Bound{c.y_max, "y_max"}}) {
      if (std::isfinite(v) && v <= 0) {
        throw std::invalid_argument(chart_name(c) + ": " + name + " " + number(v) +
                                    " is not positive on a log axis");
      }
    }
  }
}

// Axis range [lo, hi] from the data extent [data_lo, data_hi] padded by margin x span on the
// sides not fixed by fixed_lo / fixed_hi (NaN: not fixed). Values in axis units (log10 for a log
// axis); `unit` is the padding used for an empty span.
std::pair<double, double> axis_range(double data_lo, double data_hi, double fixed_lo,
                                     double fixed_hi, double margin, double unit) {
  const double span = data_hi - data_lo;
  const double pad = span > 0 ? margin * span : std::max(unit, 0.1 * std::abs(data_lo));
  double lo = std::isfinite(fixed_lo) ? fixed_lo : data_lo - pad;
  double hi = std::isfinite(fixed_hi) ? fixed_hi : data_hi + pad;
  if (!(lo < hi)) {  // one end fixed beyond all the data
    const double width = std::max(span, std::max(unit, 0.1 * std::abs(std::isfinite(fixed_lo)
                                                                          ? fixed_lo
                                                                          : fixed_hi)));
    if (std::isfinite(fixed_lo)) {
      hi = lo + width;
    } else {
      lo = hi - width;
    }
  }
  return {lo, hi};
}

// Nice ticks with a step of at least min_step (integer_x: 1).
std::vector<double> nice_ticks_min_step(double lo, double hi, int max_ticks, double min_step) {
  if (!std::isfinite(lo) || !std::isfinite(hi) || max_ticks < 1) return {};
  if (lo > hi) std::swap(lo, hi);
  if (lo == hi) return {lo};
  const double span = hi - lo;
  if (!std::isfinite(span)) return {};
  int k = static_cast<int>(std::floor(std::log10(span / max_ticks))) - 1;
  for (;; ++k) {
    for (int m : {1, 2, 5}) {
      const double step = m * pow10i(k);
      if (step < min_step * (1 - 1e-12)) continue;
      const double first = std::ceil(lo / step - 1e-9), last = std::floor(hi / step + 1e-9);
      if (last - first + 1 > max_ticks) continue;
      std::vector<double> out;
      for (double i = first; i <= last; ++i) {
        // i*m is an exact integer, so the division rounds once: 3 x 0.1 gives the double 0.3.
        out.push_back(k >= 0 ? i * m * pow10i(k) : i * m / pow10i(-k));
      }
      return out;
    }
  }
}

double tick_step(const std::vector<double>& t) { return t.size() > 1 ? t[1] - t[0] : 1.0; }

// Everything the drawing needs, worked out once.
struct Plan {
  ChartLayout l;
  std::vector<std::string> x_texts, y_texts;  // texts of l.x_ticks, l.y_ticks
  std::vector<double> y_minor;                // unlabelled grid lines (log axis)
  FittedText title, x_label, y_label;
  int tick_h = 0;                             // height of tick text
  struct LegendItem {
    size_t series;
    std::string text;
    cv::Point at;  // top-left of the item's cell, relative to the legend box
  };
  std::vector<LegendItem> legend_items;
  int legend_row_h = 0;
  struct RefLabel {
    std::string text;
    cv::Rect box;     // background box
    cv::Point org;    // text baseline start
  };
  std::vector<RefLabel> ref_labels;
};

// Liang-Barsky: clips segment a-b to r (inclusive bounds); false if nothing is left.
bool clip_segment(cv::Point2d& a, cv::Point2d& b, const cv::Rect2d& r, double* t0_out = nullptr,
                  double* t1_out = nullptr) {
  double t0 = 0, t1 = 1;
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double p[4] = {-dx, dx, -dy, dy};
  const double q[4] = {a.x - r.x, r.x + r.width - a.x, a.y - r.y, r.y + r.height - a.y};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0) {
      if (q[i] < 0) return false;
      continue;
    }
    const double t = q[i] / p[i];
    if (p[i] < 0) {
      t0 = std::max(t0, t);
    } else {
      t1 = std::min(t1, t);
    }
    if (t0 > t1) return false;
  }
  const cv::Point2d a0 = a;
  a = a0 + t0 * (b - a0);
  b = a0 + t1 * (b - a0);
  if (t0_out) *t0_out = t0;
  if (t1_out) *t1_out = t1;
  return true;
}

// The plot rect grown by a margin: where lines are clipped before drawing (keeps the fixed-point
// coordinates small; the sub-image clips the rest).
cv::Rect2d clip_rect(const cv::Rect& plot) {
  return cv::Rect2d(plot.x - 20.0, plot.y - 20.0, plot.width + 40.0, plot.height + 40.0);
}

// Runs of consecutive usable points of a series, in image pixels.
std::vector<std::vector<cv::Point2d>> pixel_runs(const ChartLayout& l, const ChartSeries& s) {
  std::vector<std::vector<cv::Point2d>> runs(1);
  for (size_t k = 0; k < s.x.size(); ++k) {
    if (!usable(s.x[k], s.y[k], l.log_y)) {
      if (!runs.back().empty()) runs.emplace_back();
      continue;
    }
    runs.back().push_back(l.to_pixel_exact(s.x[k], s.y[k]));
  }
  if (runs.back().empty()) runs.pop_back();
  return runs;
}

bool has_band(const ChartSeries& s) { return s.lo.size() == s.x.size() && s.hi.size() == s.x.size() && !s.x.empty(); }

// Polygons of a series' band (runs of x where x, lo and hi are usable), in image pixels.
std::vector<std::vector<cv::Point2d>> band_polygons(const ChartLayout& l, const ChartSeries& s) {
  std::vector<std::vector<cv::Point2d>> out;
  if (!has_band(s)) return out;
  std::vector<size_t> run;
  auto flush = [&] {
    if (run.size() >= 2) {
      std::vector<cv::Point2d> poly;
      for (size_t k : run) poly.push_back(l.to_pixel_exact(s.x[k], s.hi[k]));
      for (auto it = run.rbegin(); it != run.rend(); ++it) poly.push_back(l.to_pixel_exact(s.x[*it], s.lo[*it]));
      out.push_back(poly);
    }
    run.clear();
  };
  for (size_t k = 0; k < s.x.size(); ++k) {
    if (usable(s.x[k], s.lo[k], l.log_y) && usable(s.x[k], s.hi[k], l.log_y)) {
      run.push_back(k);
    } else {
      flush();
    }
  }
  flush();
  return out;
}

// Pixels of the plot (plot-local mask) that data or reference lines cover.
cv::Mat data_mask(const LineChart& c, const ChartLayout& l) {
  cv::Mat mask(l.plot.size(), CV_8UC1, cv::Scalar(0));
  const cv::Point2d tl(l.plot.x, l.plot.y);
  const cv::Rect2d cr = clip_rect(l.plot);
  auto local = [&](const cv::Point2d& p) {
    return cv::Point(cvRound(p.x - tl.x), cvRound(p.y - tl.y));
  };
  for (const ChartSeries& s : c.series) {
    for (const auto& poly : band_polygons(l, s)) {
      std::vector<cv::Point> q;
      for (const auto& p : poly) q.push_back(local(p));
      cv::fillPoly(mask, std::vector<std::vector<cv::Point>>{q}, cv::Scalar(255));
    }
    for (const auto& run : pixel_runs(l, s)) {
      for (size_t k = 0; k < run.size(); ++k) {
        if (cr.contains(run[k])) cv::circle(mask, local(run[k]), 5, cv::Scalar(255), cv::FILLED);
        if (k == 0) continue;
        cv::Point2d a = run[k - 1], b = run[k];
        if (clip_segment(a, b, cr)) cv::line(mask, local(a), local(b), cv::Scalar(255), 4);
      }
    }
  }
  for (const auto& [y, text] : c.y_lines) {
    if (!usable(l.x0, y, l.log_y)) continue;
    const double py = l.to_pixel_exact(l.x0, y).y;
    if (py < l.plot.y - 1 || py > l.plot.br().y) continue;
    cv::line(mask, {0, cvRound(py - tl.y)}, {mask.cols - 1, cvRound(py - tl.y)}, cv::Scalar(255),
             3);
  }
  return mask;
}

int covered(const cv::Mat& mask, const cv::Rect& plot, const cv::Rect& r) {
  const cv::Rect local = (r - plot.tl()) & cv::Rect(0, 0, mask.cols, mask.rows);
  return local.empty() ? 0 : cv::countNonZero(mask(local));
}

// y ticks for the plot height: labelled ticks and texts, and (log) unlabelled minor lines.
void plan_y_ticks(Plan& p) {
  ChartLayout& l = p.l;
  const int gap = p.tick_h + 10;  // minimum distance between labelled ticks
  l.y_ticks.clear();
  p.y_texts.clear();
  p.y_minor.clear();
  if (!l.log_y) {
    // About one per 45 px, but at least two where they fit.
    int max_ticks = std::clamp(l.plot.height / 45, 3, 11);
    l.y_ticks = nice_ticks(l.y0, l.y1, max_ticks);
    while (l.y_ticks.size() < 2 && max_ticks < l.plot.height / gap) {
      l.y_ticks = nice_ticks(l.y0, l.y1, ++max_ticks);
    }
    for (double v : l.y_ticks) p.y_texts.push_back(tick_text(v, tick_step(l.y_ticks)));
    return;
  }
  const double d0 = std::log10(l.y0), d1 = std::log10(l.y1);
  const double px_per_decade = (l.plot.height - 1) / (d1 - d0);
  std::vector<double> ticks =
      log_ticks(l.y0, l.y1, std::max(2, static_cast<int>(l.plot.height / gap) + 1));
  const bool label_25 = px_per_decade * std::log10(2.0) >= gap;
  const bool minor_lines = px_per_decade >= 40;
  for (int k = static_cast<int>(std::floor(d0)) - 1; k <= static_cast<int>(std::ceil(d1)); ++k) {
    for (int m = 2; m <= 9; ++m) {
      const double v = m * pow10i(k);
      if (v < l.y0 || v > l.y1) continue;
      if (label_25 && (m == 2 || m == 5)) {
        ticks.push_back(v);
      } else if (minor_lines) {
        p.y_minor.push_back(v);
      }
    }
  }
  if (ticks.size() < 2) {
    // Less than a decade: linear round values, as many as keep the top ones apart.
    p.y_minor.clear();
    for (int m = 10; m >= 2; --m) {
      ticks = nice_ticks(l.y0, l.y1, m);
      double min_gap = std::numeric_limits<double>::infinity();
      for (size_t i = 1; i < ticks.size(); ++i) {
        min_gap = std::min(min_gap, l.to_pixel_exact(l.x0, ticks[i - 1]).y -
                                        l.to_pixel_exact(l.x0, ticks[i]).y);
      }
      if (min_gap >= gap) break;
    }
    l.y_ticks = ticks;
    for (double v : ticks) p.y_texts.push_back(tick_text(v, tick_step(ticks)));
    return;
  }
  std::sort(ticks.begin(), ticks.end());
  l.y_ticks = ticks;
  for (double v : ticks) p.y_texts.push_back(tick_text(v, v));
}

// x ticks for the plot width: as many as fit with their texts apart.
void plan_x_ticks(Plan& p, const LineChart& c) {
  ChartLayout& l = p.l;
  const double min_step = c.integer_x ? 1.0 : 0.0;
  for (int m = std::clamp(l.plot.width / 70, 3, 15); m >= 1; --m) {
    l.x_ticks = nice_ticks_min_step(l.x0, l.x1, m, min_step);
    p.x_texts.clear();
    int widest = 0;
    for (double v : l.x_ticks) {
      p.x_texts.push_back(tick_text(v, c.integer_x ? std::max(1.0, tick_step(l.x_ticks))
                                                   : tick_step(l.x_ticks)));
      widest = std::max(widest, text_size(p.x_texts.back(), kTickScale, 1).width);
    }
    const double step_px =
        l.x_ticks.size() > 1 ? tick_step(l.x_ticks) / (l.x1 - l.x0) * (l.plot.width - 1) : 1e9;
    if (step_px >= widest + 16) return;
  }
}

// Places the labels of the reference lines inside the plot where they cover the least data
// (above or below the line, at its right or left end); marks them in the mask.
void plan_ref_labels(Plan& p, const LineChart& c, cv::Mat& mask) {
  const ChartLayout& l = p.l;
  p.ref_labels.clear();
  for (const auto& [y, text] : c.y_lines) {
    if (text.empty() || !usable(l.x0, y, l.log_y)) continue;
    const double py = l.to_pixel_exact(l.x0, y).y;
    if (py < l.plot.y || py > l.plot.br().y - 1) continue;
    Plan::RefLabel r;
    r.text = ellipsize(text, kRefScale, 1, l.plot.width / 2);
    int base = 0;
    const cv::Size sz = text_size(r.text, kRefScale, 1, &base);
    const int line = cvRound(py);
    std::vector<cv::Point> orgs;  // baseline starts
    for (bool above : {true, false}) {
      const int y_base = above ? line - 3 - base : line + 4 + sz.height;
      orgs.emplace_back(l.plot.br().x - 6 - sz.width, y_base);
      orgs.emplace_back(l.plot.x + 6, y_base);
    }
    int best = -1, best_cost = std::numeric_limits<int>::max();
    for (size_t i = 0; i < orgs.size(); ++i) {
      const cv::Rect box(orgs[i].x - 2, orgs[i].y - sz.height - 2, sz.width + 4,
                         sz.height + base + 3);
      if ((box & l.plot) != box) continue;
      const int cost = covered(mask, l.plot, box);
      if (cost < best_cost) {
        best_cost = cost;
        best = static_cast<int>(i);
      }
    }
    if (best < 0) continue;  // the plot is too small for the label
    r.org = orgs[best];
    r.box = cv::Rect(r.org.x - 2, r.org.y - sz.height - 2, sz.width + 4, sz.height + base + 3);
    cv::rectangle(mask, r.box - l.plot.tl(), cv::Scalar(255), cv::FILLED);
    p.ref_labels.push_back(r);
  }
}

// Lays out title, plot, ticks and axis labels for an image w x h of which right_extra pixels on
// the right and bottom_extra at the bottom are kept for the legend.
void lay_out_axes(Plan& p, const LineChart& c, int w, int h, int right_extra, int bottom_extra) {
  ChartLayout& l = p.l;
  // Vertical: title, plot, tick texts, x label.
  const int top = c.title.empty() ? kEdge + p.tick_h : kEdge + p.title.size.height + 18;
  int bottom = kTickLen + kTickGap + p.tick_h + kEdge + bottom_extra;
  if (!c.x_label.empty()) bottom += kLabelGap + p.x_label.size.height + p.x_label.baseline;
  l.plot.y = top;
  l.plot.height = h - top - bottom;
  l.plot.x = 0;
  l.plot.width = w;  // provisional, for the y ticks only

  // Left: y label (rotated), y tick texts.
  plan_y_ticks(p);
  int y_text_w = 0;
  for (const auto& s : p.y_texts) y_text_w = std::max(y_text_w, text_size(s, kTickScale, 1).width);
  p.y_label = fit_text(c.y_label, l.plot.height, kLabelScale, kLabelScaleMin, 1);
  int left = kEdge + y_text_w + kTickGap + kTickLen;
  if (!c.y_label.empty()) left += p.y_label.size.height + p.y_label.baseline + kLabelGap;

  // Right: room for half the last x tick text (unless the legend is there).
  int right = kEdge + 8;
  for (int pass = 0; pass < 2; ++pass) {
    l.plot.x = left;
    l.plot.width = w - left - right - right_extra;
    plan_x_ticks(p, c);
    int need = kEdge + 8;
    if (!p.x_texts.empty() && right_extra == 0) {
      const double last_px = l.to_pixel_exact(l.x_ticks.back(), l.y1).x;
      const int half = text_size(p.x_texts.back(), kTickScale, 1).width / 2;
      need = std::max(need, cvRound(last_px + half) - (l.plot.br().x - 1) + kEdge);
    }
    if (need <= right) break;
    right = need;
  }
}

// Legend items one per row; returns the box size.
cv::Size stack_legend(Plan& p, const LineChart& c, const std::vector<size_t>& series,
                      int max_text_w) {
  p.legend_items.clear();
  int widest = 0;
  for (size_t i : series) {
    const std::string t = ellipsize(c.series[i].label, kLegendScale, 1, max_text_w);
    widest = std::max(widest, text_size(t, kLegendScale, 1).width);
    const cv::Point at(kLegendPad, kLegendPad + p.legend_row_h * int(p.legend_items.size()));
    p.legend_items.push_back({i, t, at});
  }
  return cv::Size(2 * kLegendPad + kSwatch + 8 + widest,
                  2 * kLegendPad - 4 + p.legend_row_h * int(series.size()));
}

// Legend items side by side in rows at most max_w wide; returns the box size.
cv::Size flow_legend(Plan& p, const LineChart& c, const std::vector<size_t>& series, int max_w) {
  constexpr int kSpacing = 20;
  p.legend_items.clear();
  const int inner = max_w - 2 * kLegendPad;
  int x = 0, row = 0, width = 0;
  for (size_t i : series) {
    const std::string t = ellipsize(c.series[i].label, kLegendScale, 1, inner - kSwatch - 8);
    const int item_w = kSwatch + 8 + text_size(t, kLegendScale, 1).width;
    if (x > 0 && x + item_w > inner) {
      x = 0;
      ++row;
    }
    p.legend_items.push_back({i, t, cv::Point(kLegendPad + x, kLegendPad + p.legend_row_h * row)});
    width = std::max(width, x + item_w);
    x += item_w + kSpacing;
  }
  return cv::Size(2 * kLegendPad + width, 2 * kLegendPad - 4 + p.legend_row_h * (row + 1));
}

Plan plan_chart(const LineChart& c, int w, int h) {
  validate(c, w, h);
  Plan p;
  ChartLayout& l = p.l;
  l.log_y = c.log_y;

  // Data extent.
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double xlo = kInf, xhi = -kInf, ylo = kInf, yhi = -kInf;
  for (const ChartSeries& s : c.series) {
    for (size_t k = 0; k < s.x.size(); ++k) {
      if (!usable(s.x[k], s.y[k], c.log_y)) continue;
      xlo = std::min(xlo, s.x[k]);
      xhi = std::max(xhi, s.x[k]);
      ylo = std::min(ylo, s.y[k]);
      yhi = std::max(yhi, s.y[k]);
      if (has_band(s)) {
        for (double v : {s.lo[k], s.hi[k]}) {
          if (!usable(s.x[k], v, c.log_y)) continue;
          ylo = std::min(ylo, v);
          yhi = std::max(yhi, v);
        }
      }
    }
  }
  if (!(xlo <= xhi)) {
    throw std::invalid_argument(chart_name(c) + ": no finite point to draw" +
                                (c.log_y ? " (y > 0 on the log axis)" : "") + " in " +
                                std::to_string(c.series.size()) + " series");
  }
  for (const auto& yl : c.y_lines) {
    if (!usable(0.0, yl.first, c.log_y)) continue;
    ylo = std::min(ylo, yl.first);
    yhi = std::max(yhi, yl.first);
  }
  std::tie(l.x0, l.x1) = axis_range(xlo, xhi, c.x_min, c.x_max, 0.03, 1.0);
  if (c.log_y) {
    const auto [a, b] = axis_range(std::log10(ylo), std::log10(yhi), std::log10(c.y_min),
                                   std::log10(c.y_max), 0.05, 0.5);
    l.y0 = std::isfinite(c.y_min) ? c.y_min : std::pow(10.0, a);
    l.y1 = std::isfinite(c.y_max) ? c.y_max : std::pow(10.0, b);
  } else {
    std::tie(l.y0, l.y1) = axis_range(ylo, yhi, c.y_min, c.y_max, 0.05, 1.0);
  }

  p.tick_h = text_size("0123456789", kTickScale, 1).height;
  p.title = fit_text(c.title, w - 2 * kEdge, kTitleScale, kTitleScaleMin, 2);
  p.x_label = fit_text(c.x_label, w - 2 * kEdge, kLabelScale, kLabelScaleMin, 1);
  lay_out_axes(p, c, w, h, 0, 0);
  if (l.plot.width < 40 || l.plot.height < 40) {
    throw std::invalid_argument(chart_name(c) + ": image size " + std::to_string(w) + " x " +
                                std::to_string(h) + " leaves no room for the plot");
  }
  cv::Mat mask = data_mask(c, l);
  plan_ref_labels(p, c, mask);

  std::vector<size_t> in_legend;
  for (size_t i = 0; i < c.series.size(); ++i) {
    if (!c.series[i].label.empty() && has_usable_point(c.series[i], c.log_y)) {
      in_legend.push_back(i);
    }
  }
  if (in_legend.empty()) return p;
  int base = 0;
  p.legend_row_h = text_size("Ag", kLegendScale, 1, &base).height + base + 8;

  // 1. Inside the plot where it covers no data (nor reference lines and their labels).
  const cv::Size column = stack_legend(p, c, in_legend, w * 3 / 10);
  const cv::Rect& r = l.plot;
  const int xl = r.x + kLegendInset, xr = r.br().x - kLegendInset - column.width,
            xc = r.x + (r.width - column.width) / 2;
  const int yt = r.y + kLegendInset, yb = r.br().y - kLegendInset - column.height,
            ym = r.y + (r.height - column.height) / 2;
  const cv::Point corners[] = {{xr, yt}, {xl, yt}, {xr, yb}, {xl, yb},
                               {xc, yt}, {xc, yb}, {xr, ym}, {xl, ym}};
  cv::Rect best(xl, yt, column.width, column.height);
  int best_cost = std::numeric_limits<int>::max();
  for (const cv::Point& tl : corners) {
    const cv::Rect cand(tl, column);
    if ((cand & r) != cand) continue;
    const int cost = covered(mask, r, cand);
    if (cost < best_cost) {
      best_cost = cost;
      best = cand;
    }
  }
  if (best_cost == 0) {
    l.legend = best;
    return p;
  }

  // 2. Right of the plot, when that leaves the plot most of the width.
  if (column.width + kLegendGap + kEdge <= w * 2 / 5 && column.height <= r.height) {
    lay_out_axes(p, c, w, h, column.width + kLegendGap, 0);
    l.legend = cv::Rect(cv::Point(l.plot.br().x + kLegendGap, l.plot.y), column);
    mask = data_mask(c, l);
    plan_ref_labels(p, c, mask);
    return p;
  }

  // 3. Below the x label, in rows, when that leaves the plot a third of the height.
  Plan below = p;
  const cv::Size rows = flow_legend(below, c, in_legend, w - 2 * kEdge);
  lay_out_axes(below, c, w, h, 0, rows.height + kLabelGap);
  if (below.l.plot.height >= std::max(80, h / 3) && below.l.plot.width >= 40) {
    below.l.legend = cv::Rect(cv::Point((w - rows.width) / 2, h - kEdge - rows.height), rows);
    mask = data_mask(c, below.l);
    plan_ref_labels(below, c, mask);
    return below;
  }

  // 4. Inside, covering the least data.
  l.legend = best;
  return p;
}

// Polyline with a pattern; the dash phase runs on along the line.
void pattern_line(Canvas& canvas, const std::vector<cv::Point2d>& pts, const cv::Scalar& colour,
                  Pattern pattern, const cv::Rect2d& clip) {
  const double on = pattern == Pattern::kDashed ? 10.0 : 2.0;
  const double off = pattern == Pattern::kDashed ? 6.0 : 5.0;
  double phase = 0;  // distance along the line, modulo on + off
  for (size_t k = 1; k < pts.size(); ++k) {
    const double len = cv::norm(pts[k] - pts[k - 1]);
    cv::Point2d a = pts[k - 1], b = pts[k];
    double t0 = 0, t1 = 1;
    if (len > 0 && clip_segment(a, b, clip, &t0, &t1)) {
      if (pattern == Pattern::kSolid) {
        canvas.line(a, b, colour, kLineThickness);
      } else {
        const cv::Point2d dir = (pts[k] - pts[k - 1]) / len;
        // Walk from the clipped start; s is the distance from pts[k-1].
        double s = t0 * len;
        double pos = std::fmod(phase + s, on + off);
        while (s < t1 * len) {
          const bool is_on = pos < on;
          const double piece = std::min((is_on ? on : on + off) - pos, t1 * len - s);
          if (is_on && piece > 0) {
            canvas.line(pts[k - 1] + dir * s, pts[k - 1] + dir * (s + piece), colour, kLineThickness);
          }
          s += piece;
          pos = std::fmod(pos + piece, on + off);
        }
      }
    }
    phase = std::fmod(phase + len, on + off);
  }
}

void draw_series(Canvas& c, const ChartLayout& l, const ChartSeries& s, size_t i) {
  const cv::Scalar colour = scalar(chart_series_colour(i));
  const Pattern pattern = series_pattern(s, i);
  const cv::Rect2d clip = clip_rect(l.plot);
  for (const auto& run : pixel_runs(l, s)) {
    pattern_line(c, run, colour, pattern, clip);
    for (const auto& q : run) {
      if (!clip.contains(q)) continue;
      if (s.markers) {
        c.disc(q, kMarkerRadius, colour);
      } else if (run.size() == 1) {  // a lone point would not show at all
        c.disc(q, kLineThickness, colour);
      }
    }
  }
}

void draw_legend(Canvas& all, const Plan& p, const LineChart& chart) {
  const cv::Rect& r = p.l.legend;
  if (r.empty()) return;
  all.fill_rect(r, kBackground);
  all.frame_rect(r, kFrame);
  const cv::Mat& img = all.mat();
  const int text_h = text_size("Ag", kLegendScale, 1).height;
  for (const auto& item : p.legend_items) {
    const ChartSeries& s = chart.series[item.series];
    const double cy = r.y + item.at.y + p.legend_row_h / 2.0 - 2;
    const cv::Point2d a(r.x + item.at.x, cy), b(r.x + item.at.x + kSwatch, cy);
    const cv::Scalar colour = scalar(chart_series_colour(item.series));
    pattern_line(all, {a, b}, colour, series_pattern(s, item.series),
                     cv::Rect2d(0, 0, img.cols, img.rows));
    if (s.markers) all.disc((a + b) / 2, kMarkerRadius, colour);
    all.text(item.text, {b.x + 8, cy + text_h / 2.0}, kLegendScale, kText);
  }
}

}  // namespace

cv::Point2d ChartLayout::to_pixel_exact(double x, double y) const {
  const double fx = (x - x0) / (x1 - x0);
  const double fy = log_y ? (std::log10(y) - std::log10(y0)) / (std::log10(y1) - std::log10(y0))
                          : (y - y0) / (y1 - y0);
  return cv::Point2d(plot.x + fx * (plot.width - 1), plot.y + (1.0 - fy) * (plot.height - 1));
}

cv::Point ChartLayout::to_pixel(double x, double y) const {
  const cv::Point2d p = to_pixel_exact(x, y);
  auto round = [](double v) { return cvRound(std::clamp(v, -1e9, 1e9)); };
  return cv::Point(round(p.x), round(p.y));
}

std::vector<double> nice_ticks(double lo, double hi, int max_ticks) {
  return nice_ticks_min_step(lo, hi, max_ticks, 0.0);
}

std::vector<double> log_ticks(double lo, double hi, int max_ticks) {
  if (!(lo > 0) || !std::isfinite(lo) || !std::isfinite(hi) || hi < lo || max_ticks < 1) return {};
  const int a = static_cast<int>(std::ceil(std::log10(lo) - 1e-9));
  const int b = static_cast<int>(std::floor(std::log10(hi) + 1e-9));
  if (a > b) return {};
  for (int every = 1;; every = every < 3 ? every + 1 : every == 3 ? 5 : every * 2) {
    std::vector<double> out;
    for (int k = a; k <= b; ++k) {
      if (k % every == 0) out.push_back(pow10i(k));
    }
    if (static_cast<int>(out.size()) <= max_ticks || every > b - a) {
      if (out.empty()) out.push_back(pow10i(a));
      return out;
    }
  }
}

cv::Vec3b chart_series_colour(size_t i) {
  // Okabe & Ito (2008), BGR: blue, vermillion, bluish green, orange, reddish purple, sky blue,
  // black. Their yellow is left out (too faint on white).
  static const cv::Vec3b kPalette[kPaletteSize] = {
      {178, 114, 0}, {0, 94, 213}, {115, 158, 0}, {0, 159, 230},
      {167, 121, 204}, {233, 180, 86}, {0, 0, 0}};
  return kPalette[i % kPaletteSize];
}

ChartLayout chart_layout(const LineChart& chart, int width_px, int height_px) {
  return plan_chart(chart, width_px, height_px).l;
}

namespace {

// The chart into an image and, with `svg`, the same primitives into an SVG document.
cv::Mat draw_chart(const LineChart& chart, int width_px, int height_px, Svg* svg) {
  const Plan p = plan_chart(chart, width_px, height_px);
  const ChartLayout& l = p.l;
  cv::Mat img(height_px, width_px, CV_8UC3, kBackground);
  const cv::Rect& r = l.plot;
  Canvas all(img, cv::Rect(0, 0, img.cols, img.rows), kPixelCentre, svg);

  // Grid, minor lines first.
  for (double v : p.y_minor) {
    const int y = l.to_pixel(l.x0, v).y;
    all.pixel_line({r.x, y}, {r.br().x - 1, y}, kMinorGrid);
  }
  for (double v : l.y_ticks) {
    const int y = l.to_pixel(l.x0, v).y;
    all.pixel_line({r.x, y}, {r.br().x - 1, y}, kGrid);
  }
  for (double v : l.x_ticks) {
    const int x = l.to_pixel(v, l.y1).x;
    all.pixel_line({x, r.y}, {x, r.br().y - 1}, kGrid);
  }

  // Reference lines, data, reference labels.
  Canvas plot(img, r, kPixelCentre, svg);
  for (const auto& [y, text] : chart.y_lines) {
    if (!usable(l.x0, y, l.log_y)) continue;
    const int py = l.to_pixel(l.x0, y).y;
    if (py >= r.y && py < r.br().y) all.pixel_line({r.x, py}, {r.br().x - 1, py}, kRefLine);
  }
  for (size_t i = 0; i < chart.series.size(); ++i) {
    for (const auto& poly : band_polygons(l, chart.series[i])) {
      plot.polygon(poly, scalar(chart_series_colour(i)), kBandAlpha);
    }
  }
  for (size_t i = 0; i < chart.series.size(); ++i) draw_series(plot, l, chart.series[i], i);
  for (const auto& ref : p.ref_labels) {
    all.fill_rect(ref.box, kBackground);
    all.text(ref.text, ref.org, kRefScale, kSubText);
  }

  // Frame and tick marks around the plot, then their texts.
  all.frame_rect(cv::Rect(cv::Point(r.x - 1, r.y - 1), r.br() + cv::Point(1, 1)), kFrame);
  for (size_t i = 0; i < l.x_ticks.size(); ++i) {
    const int x = l.to_pixel(l.x_ticks[i], l.y1).x;
    all.pixel_line({x, r.br().y}, {x, r.br().y + kTickLen}, kFrame);
    all.text(p.x_texts[i], {double(x), double(r.br().y + kTickLen + kTickGap + p.tick_h)},
             kTickScale, kSubText, 1, 1);
  }
  for (size_t i = 0; i < l.y_ticks.size(); ++i) {
    const int y = l.to_pixel(l.x0, l.y_ticks[i]).y;
    all.pixel_line({r.x - 1 - kTickLen, y}, {r.x - 1, y}, kFrame);
    all.text(p.y_texts[i], {double(r.x - 1 - kTickLen - kTickGap), y + p.tick_h / 2.0},
             kTickScale, kSubText, 1, 2);
  }

  // Legend, axis labels, title.
  draw_legend(all, p, chart);
  if (!p.x_label.text.empty()) {
    const double y = r.br().y + kTickLen + kTickGap + p.tick_h + kLabelGap + p.x_label.size.height;
    all.text(p.x_label.text, {r.x + r.width / 2.0, y}, p.x_label.scale, kText, 1, 1);
  }
  if (!p.y_label.text.empty()) {
    const int x = kEdge + (p.y_label.size.height + p.y_label.baseline + 4) / 2;
    all.text_up(p.y_label.text, {x, r.y + r.height / 2}, p.y_label.scale, kText, p.y_label.thickness);
  }
  if (!p.title.text.empty()) {
    const double cx = std::clamp(r.x + r.width / 2.0, kEdge + p.title.size.width / 2.0,
                                 width_px - kEdge - p.title.size.width / 2.0);
    all.text(p.title.text, {cx, double(kEdge + p.title.size.height)}, p.title.scale, kBlack,
             p.title.thickness, 1);
  }
  return img;
}

}  // namespace

cv::Mat draw_line_chart(const LineChart& chart, int width_px, int height_px) {
  return draw_chart(chart, width_px, height_px, nullptr);
}

std::string line_chart_svg(const LineChart& chart, int width_px, int height_px) {
  Svg svg(width_px, height_px);
  draw_chart(chart, width_px, height_px, &svg);
  return svg.document();
}

std::string line_chart_csv(const LineChart& chart) {
  auto number = [](double v) { return std::isfinite(v) ? fmt::format("{:.9g}", v) : std::string("nan"); };
  auto quoted = [](const std::string& s) {
    std::string q = "\"";
    for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
  };
  std::string csv = "series,x,y,lo,hi\n";
  for (const ChartSeries& s : chart.series) {
    const bool band = s.lo.size() == s.x.size() && s.hi.size() == s.x.size();
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      csv += quoted(s.label) + "," + number(s.x[i]) + "," + number(s.y[i]) + "," + (band ? number(s.lo[i]) : "") + "," +
             (band ? number(s.hi[i]) : "") + "\n";
    }
  }
  return csv;
}

void write_line_chart(const LineChart& chart, const std::string& path_png, int width_px,
                      int height_px) {
  namespace fs = std::filesystem;
  Svg svg(width_px, height_px);
  const cv::Mat img = draw_chart(chart, width_px, height_px, &svg);
  if (path_png.empty()) throw std::runtime_error("cannot write " + chart_name(chart) + ": empty path");
  const fs::path path(path_png);
  const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) {
    throw std::runtime_error("cannot write " + chart_name(chart) + " to '" + path_png +
                             "': folder '" + folder.string() + "' does not exist");
  }
  const std::string tmp = path_png + ".tmp.png";
  bool ok = false;
  std::string why;
  try {
    ok = cv::imwrite(tmp, img, {cv::IMWRITE_PNG_COMPRESSION, 6});
  } catch (const cv::Exception& e) {
    why = std::string(": ") + e.what();
  }
  if (!ok) {
    fs::remove(tmp, ec);
    throw std::runtime_error("cannot write " + chart_name(chart) + " to '" + path_png + "'" + why);
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw std::runtime_error("cannot write " + chart_name(chart) + " to '" + path_png +
                             "': " + ec.message());
  }
  write_text_file(svg_path_beside(path_png), svg.document(), chart_name(chart) + " (SVG)");
  write_text_file(fs::path(path_png).replace_extension(".csv").string(), line_chart_csv(chart), chart_name(chart) + " (CSV)");
}

}  // namespace pbnbv
