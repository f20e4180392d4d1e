#include "report/line_chart.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "core/io/json.hpp"
#include "process/processes.hpp"

namespace pbnbv {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kPaletteSize = 7;
constexpr double kGnuplotTimeoutS = 60.0;
constexpr double kBandOpacity = 0.18;

std::string chart_name(const LineChart& c) {
  return c.title.empty() ? std::string("line chart (untitled)") : "line chart '" + c.title + "'";
}

std::string series_name(const LineChart& c, std::size_t i) {
  std::string s = "series " + std::to_string(i);
  if (!c.series[i].label.empty()) s += " '" + c.series[i].label + "'";
  return s + " of " + chart_name(c);
}

std::string number(double v) { return std::isfinite(v) ? fmt::format("{:.9g}", v) : std::string("nan"); }

// A gnuplot string literal: single quotes (no escapes inside but '' for a quote), one line.
std::string quoted(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("''") : c == '\n' || c == '\r' ? std::string(" ") : std::string(1, c);
  return q + "'";
}

bool usable(double x, double y, bool log_y) { return std::isfinite(x) && std::isfinite(y) && (!log_y || y > 0); }

bool has_usable_point(const ChartSeries& s, bool log_y) {
  for (std::size_t i = 0; i < s.x.size(); ++i) {
    if (usable(s.x[i], s.y[i], log_y)) return true;
  }
  return false;
}

bool has_band(const ChartSeries& s) { return !s.x.empty() && s.lo.size() == s.x.size() && s.hi.size() == s.x.size(); }

// Integer x ticks: the smallest step 1, 2 or 5 x 10^k that gives at most 12 ticks over the data.
double integer_x_step(const LineChart& c) {
  double lo = INFINITY, hi = -INFINITY;
  for (const ChartSeries& s : c.series) {
    for (double x : s.x) {
      if (std::isfinite(x)) lo = std::min(lo, x), hi = std::max(hi, x);
    }
  }
  if (std::isfinite(c.x_min)) lo = c.x_min;
  if (std::isfinite(c.x_max)) hi = c.x_max;
  const double extent = std::isfinite(hi - lo) ? hi - lo : 1.0;
  for (double decade = 1;; decade *= 10) {
    for (double m : {1.0, 2.0, 5.0}) {
      if (extent / (m * decade) <= 12) return m * decade;
    }
  }
}

std::string range(double lo, double hi) { return "[" + (std::isfinite(lo) ? number(lo) : "*") + ":" + (std::isfinite(hi) ? number(hi) : "*") + "]"; }

}  // namespace

std::string chart_series_colour(std::size_t i) {
  static const char* kPalette[kPaletteSize] = {"#0072b2", "#d55e00", "#009e73", "#e69f00", "#cc79a7", "#56b4e9", "#000000"};
  return kPalette[i % kPaletteSize];
}

void check_line_chart(const LineChart& c) {
  bool any = false;
  for (std::size_t i = 0; i < c.series.size(); ++i) {
    const ChartSeries& s = c.series[i];
    if (s.x.size() != s.y.size()) {
      throw std::invalid_argument(series_name(c, i) + " has " + std::to_string(s.x.size()) + " x values but " +
                                  std::to_string(s.y.size()) + " y values");
    }
    if ((!s.lo.empty() || !s.hi.empty()) && (s.lo.size() != s.x.size() || s.hi.size() != s.x.size())) {
      throw std::invalid_argument(series_name(c, i) + " has " + std::to_string(s.x.size()) + " x values but a band of " +
                                  std::to_string(s.lo.size()) + " lo and " + std::to_string(s.hi.size()) + " hi values");
    }
    any = any || has_usable_point(s, c.log_y);
  }
  if (!any) {
    throw std::invalid_argument(chart_name(c) + " has no finite point" + (c.log_y ? " above 0 (log axis)" : "") + " to draw");
  }
  auto check_pair = [&](double lo, double hi, const char* lo_name, const char* hi_name) {
    if (std::isfinite(lo) && std::isfinite(hi) && !(lo < hi)) {
      throw std::invalid_argument(chart_name(c) + ": " + lo_name + " " + number(lo) + " is not below " + hi_name + " " + number(hi));
    }
  };
  check_pair(c.x_min, c.x_max, "x_min", "x_max");
  check_pair(c.y_min, c.y_max, "y_min", "y_max");
  if (c.log_y) {
    for (const auto& [v, name] : {std::pair<double, const char*>{c.y_min, "y_min"}, {c.y_max, "y_max"}}) {
      if (std::isfinite(v) && v <= 0) {
        throw std::invalid_argument(chart_name(c) + ": " + name + " " + number(v) + " is not positive on a log axis");
      }
    }
  }
}

std::string line_chart_csv(const LineChart& chart) {
  auto label = [](const std::string& s) {
    std::string q = "\"";
    for (char c : s) q += c == '"' ? std::string("\"\"") : c == '\n' || c == '\r' ? std::string(" ") : std::string(1, c);
    return q + "\"";
  };
  std::string csv = "x,y,lo,hi,series\n";
  for (const ChartSeries& s : chart.series) {
    const bool band = has_band(s);
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      csv += number(s.x[i]) + "," + number(s.y[i]) + "," + (band ? number(s.lo[i]) : "") + "," +
             (band ? number(s.hi[i]) : "") + "," + label(s.label) + "\n";
    }
  }
  return csv;
}

std::string line_chart_gnuplot(const LineChart& c, const std::string& stem, int width_px, int height_px) {
  check_line_chart(c);
  if (width_px < 240 || height_px < 160) {
    throw std::invalid_argument(chart_name(c) + ": image size " + std::to_string(width_px) + " x " + std::to_string(height_px) +
                                " is smaller than 240 x 160");
  }
  const std::string data = quoted(stem + ".csv");
  std::string gp = fmt::format(
      "# {0}.gp: draws {0}.csv into {0}.png, {0}.svg and {0}.pdf (run `gnuplot {0}.gp` in this folder).\n"
      "# Written by pbnbv; the CSV holds one row per point, series after series: x, y, lo, hi, series.\n"
      "set datafile separator comma\n"
      "set encoding utf8\n"
      "set lmargin at screen {1}\nset rmargin at screen {2}\nset bmargin at screen {3}\nset tmargin at screen {4}\n",
      stem, ChartFrame::kLeft, ChartFrame::kRight, ChartFrame::kBottom, ChartFrame::kTop);
  gp += "set title " + quoted(c.title) + " noenhanced\n";
  gp += "set xlabel " + quoted(c.x_label) + " noenhanced\n";
  gp += "set ylabel " + quoted(c.y_label) + " noenhanced\n";
  gp += "set border 3 lc rgb '#404040'\nset tics nomirror\n";
  gp += "set grid xtics ytics lc rgb '#e4e4e4' lw 1 dt 1\n";
  gp += "set key at screen " + number(ChartFrame::kRight + 0.015) + ", screen " + number(ChartFrame::kTop) +
        " left top Left reverse noenhanced samplen 2.5 spacing 1.2\n";
  gp += "set offsets graph 0.02, graph 0.02, graph 0.04, graph 0.04\n";
  gp += "set xrange " + range(c.x_min, c.x_max) + "\n";
  gp += "set yrange " + range(c.y_min, c.y_max) + "\n";
  if (c.integer_x) gp += "set xtics " + number(integer_x_step(c)) + "\nset format x '%.0f'\n";
  if (c.log_y) gp += "set logscale y 10\nset mytics 10\nset grid mytics\n";
  for (std::size_t k = 0; k < c.y_lines.size(); ++k) {
    const auto& [v, text] = c.y_lines[k];
    if (!std::isfinite(v) || (c.log_y && v <= 0)) continue;
    gp += "set arrow " + std::to_string(k + 1) + " from graph 0, first " + number(v) + " to graph 1, first " + number(v) +
          " nohead dt 3 lw 1.2 lc rgb '#6e6e6e' back\n";
    gp += "set label " + std::to_string(k + 1) + " " + quoted(text) + " at graph 0.01, first " + number(v) +
          " offset 0, 0.6 tc rgb '#505050' noenhanced front\n";
  }
  // Bands first, under every line; each series is its rows of the CSV.
  std::vector<std::string> bands, lines;
  std::size_t row = 0;
  const std::string y = c.log_y ? "($2 > 0 ? $2 : NaN)" : "($2)";
  for (std::size_t i = 0; i < c.series.size(); ++i) {
    const ChartSeries& s = c.series[i];
    const std::size_t first = row, last = row + s.x.size() - 1;
    row += s.x.size();
    if (!has_usable_point(s, c.log_y)) continue;  // nothing to draw (and no empty legend entry)
    const std::string rows = data + " skip 1 every ::" + std::to_string(first) + "::" + std::to_string(last);
    const std::string colour = "lc rgb '" + chart_series_colour(i) + "'";
    if (has_band(s)) {
      bands.push_back(rows + " using ($1):($3):($4) with filledcurves fc rgb '" + chart_series_colour(i) +
                      "' fs transparent solid " + number(kBandOpacity) + " noborder notitle");
    }
    const int pattern = static_cast<int>((i / kPaletteSize + (s.dashed ? 1 : 0)) % 3);  // solid, dashed, dotted
    lines.push_back(rows + " using ($1):" + y + " with " + (s.markers ? "linespoints pt 7 ps 0.6" : "lines") + " lw 2 " +
                    colour + " dt " + std::to_string(pattern == 0 ? 1 : pattern == 1 ? 2 : 3) + " " +
                    (s.label.empty() ? std::string("notitle") : "title " + quoted(s.label)));
  }
  std::string plot = "plot ";
  bool comma = false;
  for (const auto* part : {&bands, &lines}) {
    for (const std::string& p : *part) {
      plot += (comma ? ", \\\n     " : "") + p;
      comma = true;
    }
  }
  const double pdf_height_in = 10.0 * height_px / width_px;
  gp += fmt::format("set terminal pngcairo size {1},{2} font 'DejaVu Sans,11' background rgb 'white'\nset output '{0}.png'\n",
                    stem, width_px, height_px);
  gp += plot + "\n";
  gp += fmt::format("set terminal svg size {1},{2} font 'DejaVu Sans,11' background rgb 'white'\nset output '{0}.svg'\nreplot\n",
                    stem, width_px, height_px);
  gp += fmt::format("set terminal pdfcairo size 10in,{1}in font 'DejaVu Sans,11'\nset output '{0}.pdf'\nreplot\nunset output\n",
                    stem, number(pdf_height_in));
  return gp;
}

void write_line_chart(const LineChart& chart, const std::string& path_png, int width_px, int height_px) {
  if (path_png.empty()) throw std::runtime_error("cannot write " + chart_name(chart) + ": empty path");
  const fs::path path(path_png);
  if (path.extension() != ".png") throw std::runtime_error("cannot write " + chart_name(chart) + " to '" + path_png + "': not a .png");
  const fs::path folder = fs::absolute(path).parent_path();
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) {
    throw std::runtime_error("cannot write " + chart_name(chart) + " to '" + path_png + "': folder '" + folder.string() +
                             "' does not exist");
  }
  const std::string stem = path.stem().string();
  const std::string script = line_chart_gnuplot(chart, stem, width_px, height_px);
  write_text_atomic(line_chart_csv(chart), (folder / (stem + ".csv")).string());
  write_text_atomic(script, (folder / (stem + ".gp")).string());
  for (const char* ext : {".png", ".svg", ".pdf"}) fs::remove(folder / (stem + ext), ec);  // no old drawing passes for new
  process::Child gnuplot;
  gnuplot.name = "gnuplot";
  gnuplot.argv = {"gnuplot", stem + ".gp"};
  gnuplot.cwd = folder.string();
  gnuplot.log_path = (folder / (stem + ".gnuplot.log")).string();
  const int code = process::run(gnuplot, kGnuplotTimeoutS);
  const std::string said = process::tail_lines(gnuplot.log_path, 6);
  fs::remove(gnuplot.log_path, ec);
  if (code == 127) {
    throw std::runtime_error("cannot draw " + chart_name(chart) + ": gnuplot is not installed (Debian: gnuplot-nox; scripts/setup installs it); its data is in " +
                             (folder / (stem + ".csv")).string());
  }
  if (code != 0) {
    throw std::runtime_error("cannot draw " + chart_name(chart) + ": gnuplot " + (folder / (stem + ".gp")).string() +
                             (code == 128 + 9 ? " took over " + number(kGnuplotTimeoutS) + " s" : " exited " + std::to_string(code)) +
                             (said.empty() ? std::string() : ":\n" + said));
  }
  for (const char* ext : {".png", ".svg", ".pdf"}) {
    if (!fs::exists(folder / (stem + ext))) {
      throw std::runtime_error("cannot draw " + chart_name(chart) + ": gnuplot wrote no " + (folder / (stem + ext)).string() +
                               (said.empty() ? std::string() : ":\n" + said));
    }
  }
}

}  // namespace pbnbv
