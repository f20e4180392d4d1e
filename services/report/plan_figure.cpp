#include "report/plan_figure.hpp"
#include "core/base/atomic_file.hpp"

#include "core/io/image_codec.hpp"
#include "report/canvas.hpp"

#include <fmt/format.h>
#include "core/base/units.hpp"

#include <Eigen/Eigenvalues>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <sstream>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace pbnbv {
namespace {

using drawing::Canvas;
using drawing::Svg;
using drawing::kBlack;
using drawing::kFont;
using drawing::kFrame;
using drawing::kOne;
using drawing::kShift;
using drawing::kSubText;
using drawing::kText;
using drawing::scalar;
using drawing::text_size;



// Layout (pixels).
constexpr int kWidth = 1500;
constexpr int kTitleBlock = 40;   // header height without text lines
constexpr int kLineStep = 20;     // per text line under the title
constexpr int kLabelBlock = 26;   // panel labels above the panels
constexpr int kPanel = 440;       // panels 1 and 2 are kPanel x kPanel
constexpr int kBottom = 14;
constexpr int kMapW = 480;        // panel 3: kMapW x kMapW / 2
constexpr int kMapStrip = 18;     // above panel 3: the sector names

// Figure coordinates: pixel i covers [i, i+1), so its centre is at i + 0.5.
constexpr double kPixelCentre = 0.5;

const cv::Scalar kGrid(236, 236, 236);
const cv::Scalar kSectorLine(120, 120, 120);
const cv::Scalar kAllowedShade(228, 246, 230);  // light green
const cv::Scalar kBoxColour(70, 70, 70);
const cv::Scalar kOutsideColour(175, 175, 175);
const cv::Scalar kUnscoredColour(120, 120, 120);
const cv::Scalar kExcludedColour(30, 30, 210);

cv::Scalar mix(const cv::Scalar& a, const cv::Scalar& b, double t) {  // (1-t) a + t b
  return cv::Scalar(a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t,
                    a[2] + (b[2] - a[2]) * t);
}

cv::Scalar darker(const cv::Scalar& c, double f) { return mix(c, kBlack, f); }

// Viridis-like colour for t in [0, 1] (OpenCV's VIRIDIS map).
cv::Scalar colour_map(double t) {
  static const cv::Mat lut = [] {
    cv::Mat ramp(256, 1, CV_8UC1);
    for (int i = 0; i < 256; ++i) ramp.at<uint8_t>(i) = static_cast<uint8_t>(i);
    cv::Mat out;
    cv::applyColorMap(ramp, out, cv::COLORMAP_VIRIDIS);
    return out;
  }();
  const int i = std::clamp(static_cast<int>(std::lround(t * 255.0)), 0, 255);
  return scalar(lut.at<cv::Vec3b>(i));
}

void validate(const PlanFigure& f) {
  const size_t n = f.candidates.size();
  if (f.quality.size() != n) {
    throw std::invalid_argument("plan figure: quality has " + std::to_string(f.quality.size()) +
                                " entries, candidates " + std::to_string(n));
  }
  if (f.status.size() != n) {
    throw std::invalid_argument("plan figure: status has " + std::to_string(f.status.size()) +
                                " entries, candidates " + std::to_string(n));
  }
  if (f.chosen < -1 || f.chosen >= static_cast<int>(n)) {
    throw std::invalid_argument("plan figure: chosen " + std::to_string(f.chosen) +
                                " is out of range for " + std::to_string(n) + " candidates");
  }
}

// A "nice" grid step (1, 2 or 5 x 10^k) giving a few lines over `span`.
double nice_step(double span) {
  const double raw = span / 8.0;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0}) {
    if (m * p >= raw) return m * p;
  }
  return 10.0 * p;
}

std::string metres(double v) {
  if (v >= 1.0) return fmt::format("{:g} m", v);
  return fmt::format("{:g} cm", v * 100.0);
}

struct FRange {
  bool any = false;
  double lo = 0, hi = 0;
  double t(double f) const { return hi > lo ? (f - lo) / (hi - lo) : 0.5; }
};

FRange f_range(const PlanFigure& f) {
  FRange r;
  r.lo = std::numeric_limits<double>::infinity();
  r.hi = -r.lo;
  for (size_t i = 0; i < f.candidates.size(); ++i) {
    if (f.status[i] != CandidateStatus::kScored || !std::isfinite(f.quality[i])) continue;
    r.any = true;
    r.lo = std::min(r.lo, f.quality[i]);
    r.hi = std::max(r.hi, f.quality[i]);
  }
  if (!r.any) r.lo = r.hi = 0;
  return r;
}

bool is_allowed(const PlanFigure& f, int sector) {
  return std::find(f.allowed_sectors.begin(), f.allowed_sectors.end(), sector) !=
         f.allowed_sectors.end();
}

cv::Scalar sector_background(const PlanFigure& f, int sector) {
  return is_allowed(f, sector) ? kAllowedShade : scalar(PlanFigureColours::background());
}

bool is_scored(const PlanFigure& f, size_t i) {
  return f.status[i] == CandidateStatus::kScored && std::isfinite(f.quality[i]);
}

// Marker radii (px) as the panels draw them, for keeping labels clear of them.
constexpr double kCandidateRadius = 3.6;
constexpr double kPastRadius = 10.0;    // disc 9 and its ring
constexpr double kChosenRadius = 16.0;  // ring 15, 2 px wide
constexpr double kSectorLabelScale = 0.42;
constexpr double kLegendScale = 0.42;
constexpr int kEdge = 12;               // right edge of the figure kept free

// --- Markers, shared by the three panels ---

void candidate_marker(Canvas& c, const cv::Point2d& p, const PlanFigure& f, size_t i,
                      const FRange& range, bool pale) {
  const cv::Scalar bg = scalar(PlanFigureColours::background());
  switch (f.status[i]) {
    case CandidateStatus::kUnreachable:
      c.cross(p, 2.5, pale ? mix(kBlack, bg, 0.55) : kBlack);
      return;
    case CandidateStatus::kOutsidePartition:
      c.disc(p, 2.0, pale ? mix(kOutsideColour, bg, 0.5) : kOutsideColour);
      return;
    case CandidateStatus::kExcluded:
      c.cross(p, 2.5, pale ? mix(kExcludedColour, bg, 0.55) : kExcludedColour);
      return;
    case CandidateStatus::kScored:
      break;
  }
  if (!is_scored(f, i)) {  // scored but F not finite
    c.ring(p, 2.5, kUnscoredColour);
    return;
  }
  const cv::Scalar col = colour_map(range.t(f.quality[i]));
  if (pale) {
    c.disc(p, 3.0, mix(col, bg, 0.6));
  } else {
    c.disc(p, 3.6, col);
  }
}

void past_marker(Canvas& c, const cv::Point2d& p, int number, double r = 9.0) {
  c.disc(p, r, scalar(PlanFigureColours::past_view()));
  c.ring(p, r, kBlack, 1);
  c.text_centred(std::to_string(number), p, number >= 10 ? 0.33 : 0.4, kBlack, 1);
}

void chosen_marker(Canvas& c, const cv::Point2d& p) {
  const cv::Scalar col = scalar(PlanFigureColours::chosen());
  c.ring(p, 15.0, col, 2);
  c.disc(p, 9.5, kBlack);
  c.disc(p, 8.0, col);
}

// --- Panel 3's wrap-around ---

// The map pixels of a camera centre: its own and, within `radius` of the 0 or 360 deg edge, its
// copy at the other edge, so a marker there shows whole on both sides.
std::vector<cv::Point2d> map_pixels(const PlanFigureLayout& l, const Eigen::Vector3d& eye, double radius) {
  const Eigen::Vector2d ap = azimuth_polar_deg(eye, l.centre);
  const cv::Point2d p = sphere_map_pixel(l, ap(0), ap(1));
  std::vector<cv::Point2d> out{p};
  if (p.x - l.map.x < radius) out.push_back(p + cv::Point2d(l.map.width, 0));
  if (l.map.x + l.map.width - p.x < radius) out.push_back(p - cv::Point2d(l.map.width, 0));
  return out;
}

// --- Panels 1 and 2 ---

struct OrthoView {
  cv::Rect rect;
  int u_axis, v_axis, depth_axis;  // world axes along image x, image up, towards the viewer
  double depth_sign;               // +1: larger depth coordinate is nearer the viewer
};

cv::Point2d ortho_pixel(const PlanFigureLayout& l, const OrthoView& v, const Eigen::Vector3d& p) {
  const double s = (v.rect.width / 2.0) / l.half_width_m;
  const double cx = v.rect.x + v.rect.width / 2.0;
  const double cy = v.rect.y + v.rect.height / 2.0;
  return cv::Point2d(cx + (p[v.u_axis] - l.centre[v.u_axis]) * s,
                     cy - (p[v.v_axis] - l.centre[v.v_axis]) * s);
}

void draw_grid(Canvas& c, const PlanFigureLayout& l, const OrthoView& v, double step) {
  for (int axis : {v.u_axis, v.v_axis}) {
    const double lo = l.centre[axis] - l.half_width_m, hi = l.centre[axis] + l.half_width_m;
    for (double g = std::ceil(lo / step) * step; g <= hi; g += step) {
      const bool zero = std::abs(g) < 1e-9 * step;
      Eigen::Vector3d p = l.centre;
      p[axis] = g;
      const cv::Point2d q = ortho_pixel(l, v, p);
      const cv::Scalar col = zero ? cv::Scalar(210, 210, 210) : kGrid;
      if (axis == v.u_axis) {
        c.line({q.x, double(v.rect.y)}, {q.x, double(v.rect.br().y)}, col);
      } else {
        c.line({double(v.rect.x), q.y}, {double(v.rect.br().x), q.y}, col);
      }
    }
  }
}

void draw_sectors_top(Canvas& c, const PlanFigureLayout& l, const OrthoView& v,
                      const PlanFigure& f, bool lines) {
  if (f.beta <= 1) return;
  const cv::Point2d o = ortho_pixel(l, v, l.centre);
  const double big = 2.0 * v.rect.width;
  const double w = 2 * kPi / f.beta;
  if (!lines) {
    for (int s : f.allowed_sectors) {
      if (s < 0 || s >= f.beta) continue;
      std::vector<cv::Point2d> poly{o};
      const int steps = std::max(2, static_cast<int>(std::ceil(w / (kPi / 36))));
      for (int k = 0; k <= steps; ++k) {
        const double a = f.sector_start_rad + s * w + w * k / steps;
        poly.emplace_back(o.x + big * std::cos(a), o.y - big * std::sin(a));
      }
      c.polygon(poly, kAllowedShade);
    }
    return;
  }
  for (int s = 0; s < f.beta; ++s) {
    const double a = f.sector_start_rad + s * w;
    c.line(o, {o.x + big * std::cos(a), o.y - big * std::sin(a)}, kSectorLine);
  }
}

void draw_ellipsoids(Canvas& c, const PlanFigureLayout& l, const OrthoView& v,
                     const PlanFigure& f) {
  const double s = (v.rect.width / 2.0) / l.half_width_m;
  struct Shadow {
    cv::Point2d centre;
    double a, b, angle;
    EllipsoidClass cls;
  };
  std::vector<Shadow> shadows;
  for (const auto& e : f.ellipsoids) {
    const Eigen::Vector3d s2 = e.semi_axes.cwiseAbs2();
    const Eigen::Matrix3d m = e.axes * s2.asDiagonal() * e.axes.transpose();
    Eigen::Matrix2d b;
    b << m(v.u_axis, v.u_axis), m(v.u_axis, v.v_axis), m(v.v_axis, v.u_axis),
        m(v.v_axis, v.v_axis);
    if (!b.allFinite() || !e.centre.allFinite()) continue;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(b);
    const Eigen::Vector2d lam = es.eigenvalues().cwiseMax(0.0);
    const Eigen::Vector2d dir = es.eigenvectors().col(1);  // larger eigenvalue
    // Image y points down, so the world direction (du, dv) is (du, -dv) in the image.
    const double angle = std::atan2(-dir.y(), dir.x()) * 180.0 / kPi;
    shadows.push_back({ortho_pixel(l, v, e.centre), std::sqrt(lam(1)) * s,
                       std::sqrt(lam(0)) * s, angle, e.cls});
  }
  // Occupied first, frontier over them; each fill blended on its own.
  const double alpha = PlanFigureColours::fill_alpha();
  for (EllipsoidClass cls : {EllipsoidClass::kOccupied, EllipsoidClass::kFrontier}) {
    const cv::Scalar col = scalar(cls == EllipsoidClass::kFrontier ? PlanFigureColours::frontier()
                                                                   : PlanFigureColours::occupied());
    for (const auto& sh : shadows) {
      if (sh.cls != cls) continue;
      c.ellipse(sh.centre, sh.a, sh.b, sh.angle, col, cv::FILLED, alpha);
    }
    for (const auto& sh : shadows) {
      if (sh.cls != cls) continue;
      c.ellipse(sh.centre, sh.a, sh.b, sh.angle, darker(col, 0.25), 1);
    }
  }
}

void draw_ortho_panel(cv::Mat& fig, Svg* svg, const PlanFigureLayout& l, const OrthoView& v,
                      const PlanFigure& f, const FRange& range, bool top) {
  Canvas c(fig, v.rect, kPixelCentre, svg);
  const double step = nice_step(2.0 * l.half_width_m);
  if (top) draw_sectors_top(c, l, v, f, false);
  draw_grid(c, l, v, step);
  if (top) draw_sectors_top(c, l, v, f, true);

  if (!f.bbox.isEmpty()) {
    const Eigen::Vector3d lo = f.bbox.min(), hi = f.bbox.max();
    const cv::Point2d a = ortho_pixel(l, v, lo), b = ortho_pixel(l, v, hi);
    c.rect(a, b, kBoxColour, 1);
    c.text("B", {std::max(a.x, b.x) + 3, std::min(a.y, b.y) + 10}, 0.4, kBoxColour);
  }
  draw_ellipsoids(c, l, v, f);

  // Candidates, far ones first and paler.
  std::vector<size_t> order(f.candidates.size());
  std::iota(order.begin(), order.end(), size_t{0});
  auto depth = [&](size_t i) {
    return v.depth_sign * (f.candidates[i].translation()[v.depth_axis] - l.centre[v.depth_axis]);
  };
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return depth(a) < depth(b); });
  for (size_t i : order) {
    candidate_marker(c, ortho_pixel(l, v, f.candidates[i].translation()), f, i, range,
                     depth(i) < -1e-9);
  }

  if (f.chosen >= 0) {
    const cv::Point2d p = ortho_pixel(l, v, f.candidates[f.chosen].translation());
    const cv::Point2d o = ortho_pixel(l, v, l.centre);
    c.line(p, o, scalar(PlanFigureColours::chosen()), 2);
    c.disc(o, 3.0, scalar(PlanFigureColours::chosen()));
  }
  for (size_t k = 0; k < f.past_views.size(); ++k) {
    past_marker(c, ortho_pixel(l, v, f.past_views[k].translation()), static_cast<int>(k) + 1);
  }
  if (f.chosen >= 0) chosen_marker(c, ortho_pixel(l, v, f.candidates[f.chosen].translation()));
  if (top) {  // sector names over everything, where no marker is
    for (const auto& sl : sector_labels(l, f)) {
      if (sl.in_top) c.label(sl.text, sl.centre, kSectorLabelScale, kSectorLine, sector_background(f, sl.sector));
    }
  }
}

// --- Panel 3 ---

// The sphere map: the allowed sectors, the grid, the sector boundaries and the markers (those
// near the 0/360 deg edges at both edges: the map wraps around).
void draw_sphere_map(cv::Mat& fig, Svg* svg, const PlanFigureLayout& l, const PlanFigure& f, const FRange& range) {
  const cv::Rect& r = l.map;
  const double start_deg = f.sector_start_rad * 180.0 / kPi;
  auto wrap_deg = [](double a) { return a - 360.0 * std::floor(a / 360.0); };
  Canvas c(fig, r, kPixelCentre, svg);
  // Allowed sectors and sector boundaries.
  if (f.beta > 1) {
    for (int s : f.allowed_sectors) {
      if (s < 0 || s >= f.beta) continue;
      // The sector's azimuth span on the 0..360 map, split where it wraps.
      const double a0 = wrap_deg(start_deg + 360.0 * s / f.beta), a1 = a0 + 360.0 / f.beta;
      auto shade = [&](double lo, double hi) {
        c.polygon({sphere_map_pixel(l, lo, 0), sphere_map_pixel(l, hi, 0), sphere_map_pixel(l, hi, 180),
                   sphere_map_pixel(l, lo, 180)},
                  kAllowedShade);
      };
      if (a1 <= 360.0) {
        shade(a0, a1);
      } else {
        shade(a0, 360.0);
        shade(0.0, a1 - 360.0);
      }
    }
  }
  for (int az = 45; az < 360; az += 45) {
    c.line(sphere_map_pixel(l, az, 0), sphere_map_pixel(l, az, 180), kGrid);
  }
  for (int po = 30; po < 180; po += 30) {
    c.line(sphere_map_pixel(l, 0, po), sphere_map_pixel(l, 360, po),
           po == 90 ? cv::Scalar(205, 205, 205) : kGrid);
  }
  if (f.beta > 1) {
    for (int s = 0; s < f.beta; ++s) {
      const double a0 = wrap_deg(start_deg + 360.0 * s / f.beta);
      if (a0 > 1e-9) c.line(sphere_map_pixel(l, a0, 0), sphere_map_pixel(l, a0, 180), kSectorLine);
    }
  }
  // Markers near the 0/360 deg edges are drawn at both edges (the map wraps around).
  for (size_t i = 0; i < f.candidates.size(); ++i) {
    for (const auto& p : map_pixels(l, f.candidates[i].translation(), kCandidateRadius)) {
      candidate_marker(c, p, f, i, range, false);
    }
  }
  for (size_t k = 0; k < f.past_views.size(); ++k) {
    for (const auto& p : map_pixels(l, f.past_views[k].translation(), kPastRadius)) {
      past_marker(c, p, static_cast<int>(k) + 1);
    }
  }
  if (f.chosen >= 0) {
    for (const auto& p : map_pixels(l, f.candidates[f.chosen].translation(), kChosenRadius)) chosen_marker(c, p);
  }
}

// The colour bar of the candidates' quality, with the chosen view's mark.
void draw_colour_bar(Canvas& all, const PlanFigureLayout& l, const PlanFigure& f, const FRange& range) {
  // Colour bar.
  const cv::Rect& b = l.colour_bar;
  if (range.any) {
    for (int x = 0; x < b.width; ++x) {
      all.pixel_line({b.x + x, b.y}, {b.x + x, b.y + b.height - 1},
                     colour_map(b.width > 1 ? x / double(b.width - 1) : 0.5));
    }
  } else {
    all.fill_rect(b, cv::Scalar(240, 240, 240));
    all.text("no scored candidates", {b.x + b.width / 2.0, b.y + b.height - 3.0}, 0.4, kSubText, 1,
             1);
  }
  all.rect({double(b.x), double(b.y)}, {double(b.br().x), double(b.br().y)}, kFrame);
  all.text(f.quality_label, {b.x + b.width / 2.0, b.y - 7.0}, 0.45,
           kText, 1, 1);
  if (range.any) {
    all.text(fmt::format("{:.4g}", range.lo), {double(b.x), b.br().y + 16.0}, 0.42, kText, 1, 0);
    all.text(fmt::format("{:.4g}", range.hi), {double(b.br().x), b.br().y + 16.0}, 0.42, kText, 1, 2);
  }
  if (range.any && range.lo < 0 && range.hi > 0) {
    const double x0 = b.x + range.t(0.0) * b.width;
    all.line({x0, b.y - 3.0}, {x0, b.br().y + 3.0}, kBlack, 1);
    all.text("0", {x0, b.br().y + 16.0}, 0.42, kText, 1, 1);
  }
  if (f.chosen >= 0 && range.any && is_scored(f, f.chosen)) {
    const double x = b.x + std::clamp(range.t(f.quality[f.chosen]), 0.0, 1.0) * b.width;
    const cv::Scalar col = scalar(PlanFigureColours::chosen());
    all.line({x, b.y - 3.0}, {x, b.br().y + 3.0}, col, 3);
    all.text("chosen " + fmt::format("{:.4g}", f.quality[f.chosen]), {x, b.br().y + 16.0}, 0.42, col, 1,
             x > b.x + b.width * 0.75 ? 2 : x < b.x + b.width * 0.25 ? 0 : 1);
  }
}

// The legend, as laid out by legend_items.
void draw_legend(Canvas& all, const PlanFigureLayout& l, const PlanFigure& f) {
  auto swatch = [&all](const cv::Point2d& p, const cv::Vec3b& col) {
    const cv::Scalar c = mix(scalar(PlanFigureColours::background()), scalar(col), PlanFigureColours::fill_alpha());
    all.ellipse(p, 10, 6, 0, c, cv::FILLED);
    all.ellipse(p, 10, 6, 0, darker(scalar(col), 0.25), 1);
  };
  for (const LegendItem& it : legend_items(l, f)) {
    const cv::Point2d p = it.marker;
    switch (it.kind) {
      case LegendKind::kChosen: chosen_marker(all, p); break;
      case LegendKind::kPast: past_marker(all, p, 1); break;
      case LegendKind::kUnreachable: all.cross(p, 2.5, kBlack); break;
      case LegendKind::kOutside: all.disc(p, 2.0, kOutsideColour); break;
      case LegendKind::kOccupied: swatch(p, PlanFigureColours::occupied()); break;
      case LegendKind::kFrontier: swatch(p, PlanFigureColours::frontier()); break;
      case LegendKind::kAllowed:
        all.polygon({p + cv::Point2d(-10, -7), p + cv::Point2d(10, -7), p + cv::Point2d(10, 7),
                     p + cv::Point2d(-10, 7)},
                    kAllowedShade);
        all.rect(p + cv::Point2d(-10, -7), p + cv::Point2d(10, 7), kFrame);
        break;
      case LegendKind::kExcluded: all.cross(p, 2.5, kExcludedColour); break;
      case LegendKind::kNote: break;
    }
    all.text(it.text, it.text_org, it.kind == LegendKind::kNote ? 0.4 : kLegendScale,
             it.kind == LegendKind::kNote ? kSubText : kText);
  }
}

void draw_map_panel(cv::Mat& fig, Svg* svg, const PlanFigureLayout& l, const PlanFigure& f,
                    const FRange& range) {
  const cv::Rect& r = l.map;
  draw_sphere_map(fig, svg, l, f, range);
  Canvas all(fig, cv::Rect(0, 0, fig.cols, fig.rows), kPixelCentre, svg);
  for (const auto& sl : sector_labels(l, f)) {  // sector names in the strip above the map
    if (!sl.in_top) all.label(sl.text, sl.centre, kSectorLabelScale, kSectorLine, sector_background(f, sl.sector));
  }
  all.rect({double(r.x), double(r.y)}, {double(r.br().x), double(r.br().y)}, kFrame);
  for (int az = 0; az <= 360; az += 90) {
    all.text(std::to_string(az), sphere_map_pixel(l, az, 180) + cv::Point2d(0, 16), 0.4, kSubText,
             1, 1);
  }
  for (int po = 0; po <= 180; po += 30) {
    all.text(std::to_string(po), sphere_map_pixel(l, 0, po) + cv::Point2d(-6, 5), 0.4, kSubText, 1,
             2);
  }
  all.text("azimuth about the centre (deg)", {r.x + r.width / 2.0, r.br().y + 34.0}, 0.45, kText,
           1, 1);
  draw_colour_bar(all, l, f, range);
  draw_legend(all, l, f);
}

}  // namespace

namespace {

struct Marker {
  cv::Point2d p;
  double r;
};

// Does a box (centre c, half extents h) come within r + 1 px of p?
bool touches(const cv::Point2d& c, const cv::Point2d& h, const Marker& m) {
  const double dx = std::max(std::abs(m.p.x - c.x) - h.x, 0.0), dy = std::max(std::abs(m.p.y - c.y) - h.y, 0.0);
  return dx * dx + dy * dy < (m.r + 1.0) * (m.r + 1.0);
}

// The first spot whose box keeps clear of every marker (inside `panel`), else the one touching
// fewest.
cv::Point2d place(const std::vector<cv::Point2d>& spots, const cv::Point2d& h, const std::vector<Marker>& markers,
                  const cv::Rect& panel) {
  cv::Point2d best = spots.front();
  size_t best_n = std::numeric_limits<size_t>::max();
  for (cv::Point2d c : spots) {
    c.x = std::clamp(c.x, panel.x + h.x + 1, panel.br().x - h.x - 1);
    c.y = std::clamp(c.y, panel.y + h.y + 1, panel.br().y - h.y - 1);
    size_t n = 0;
    for (const Marker& m : markers) n += touches(c, h, m) ? 1 : 0;
    if (n == 0) return c;
    if (n < best_n) {
      best_n = n;
      best = c;
    }
  }
  return best;
}

}  // namespace

std::vector<SectorLabel> sector_labels(const PlanFigureLayout& l, const PlanFigure& f) {
  std::vector<SectorLabel> out;
  if (f.beta <= 1) return out;
  const double w = 2 * kPi / f.beta;
  const OrthoView top{l.top, 0, 1, 2, 1.0};
  std::vector<Marker> top_markers;
  for (size_t i = 0; i < f.candidates.size(); ++i) {
    top_markers.push_back({ortho_pixel(l, top, f.candidates[i].translation()), kCandidateRadius});
  }
  for (const auto& v : f.past_views) top_markers.push_back({ortho_pixel(l, top, v.translation()), kPastRadius});
  if (f.chosen >= 0) top_markers.push_back({ortho_pixel(l, top, f.candidates[f.chosen].translation()), kChosenRadius});
  const cv::Point2d o = ortho_pixel(l, top, l.centre);
  // Candidates and past views lie within this radius of the centre in the top view.
  const double ring = (l.top.width / 2.0) / 1.1;
  for (int s = 0; s < f.beta; ++s) {
    SectorLabel sl;
    sl.sector = s;
    sl.text = "s" + std::to_string(s);
    const cv::Size sz = text_size(sl.text, kSectorLabelScale, 1);
    const cv::Point2d h(sz.width / 2.0 + 3, sz.height / 2.0 + 3);
    // Top view: just outside the ring of camera centres, across the sector from its middle
    // outwards, then inwards along its middle.
    std::vector<cv::Point2d> spots;
    for (double t : {0.5, 0.4, 0.6, 0.3, 0.7, 0.2, 0.8, 0.1, 0.9}) {
      const double a = f.sector_start_rad + (s + t) * w;
      const cv::Point2d u(std::cos(a), -std::sin(a));
      const double d = ring + kCandidateRadius + 2 + h.x * std::abs(u.x) + h.y * std::abs(u.y);
      spots.push_back(o + u * d);
    }
    for (double k = 0.9; k > 0.2; k -= 0.05) {
      const double a = f.sector_start_rad + (s + 0.5) * w;
      spots.push_back(o + cv::Point2d(std::cos(a), -std::sin(a)) * (k * ring));
    }
    sl.in_top = true;
    sl.centre = place(spots, h, top_markers, l.top);
    sl.box = cv::Rect2d(sl.centre - h, sl.centre + h);
    top_markers.push_back({sl.centre, std::hypot(h.x, h.y)});  // labels keep clear of each other
    out.push_back(sl);
    // Map: in the strip above it (no marker there), over the sector's middle azimuth.
    double az = f.sector_start_rad * 180.0 / kPi + 360.0 * (s + 0.5) / f.beta;
    az -= 360.0 * std::floor(az / 360.0);
    sl.in_top = false;
    sl.centre = cv::Point2d(std::clamp(sphere_map_pixel(l, az, 0).x, l.map.x + h.x, l.map.br().x - h.x),
                            l.map.y - kMapStrip / 2.0);
    sl.box = cv::Rect2d(sl.centre - h, sl.centre + h);
    out.push_back(sl);
  }
  return out;
}

std::vector<LegendItem> legend_items(const PlanFigureLayout& l, const PlanFigure& f) {
  std::vector<std::vector<std::pair<LegendKind, std::string>>> groups = {
      {{LegendKind::kChosen, "chosen"},
       {LegendKind::kPast, "past view"},
       {LegendKind::kUnreachable, "unreachable"},
       {LegendKind::kOutside, "outside partition"}},
      {{LegendKind::kOccupied, "occupied ellipsoid"}, {LegendKind::kFrontier, "frontier ellipsoid"}}};
  if (f.beta > 1) groups[1].push_back({LegendKind::kAllowed, "allowed sectors"});
  if (std::find(f.status.begin(), f.status.end(), CandidateStatus::kExcluded) != f.status.end()) {
    groups[1].push_back({LegendKind::kExcluded, "excluded"});
  }
  std::vector<LegendItem> out;
  const double right = l.size.width - kEdge;
  double y = l.colour_bar.br().y + 44.0;
  int base = 0;
  for (const auto& g : groups) {
    double x = l.map.x;
    for (const auto& [kind, text] : g) {
      const double half = kind == LegendKind::kChosen ? 15.0 : 10.0;
      const cv::Size ts = text_size(text, kLegendScale, 1, &base);
      const double width = 2 * half + 5 + ts.width;
      if (x > l.map.x && x + width > right) {  // wrap onto a new row
        x = l.map.x;
        y += 26.0;
      }
      LegendItem it;
      it.kind = kind;
      it.text = text;
      it.marker = cv::Point2d(x + half, y - 4);
      it.text_org = cv::Point2d(x + 2 * half + 5, y);
      const double mh = kind == LegendKind::kChosen      ? 16.0
                        : kind == LegendKind::kPast      ? 10.0
                        : kind == LegendKind::kAllowed   ? 8.0
                        : kind == LegendKind::kOccupied || kind == LegendKind::kFrontier ? 7.0
                                                         : 3.5;
      const double top = std::min(y - 4 - mh, y - ts.height), bottom = std::max(y - 4 + mh, y + base);
      it.box = cv::Rect2d(x, top, width, bottom - top);
      out.push_back(it);
      x += width + 18;
    }
    y += 26.0;
  }
  LegendItem note;
  note.kind = LegendKind::kNote;
  note.text = "paler markers: far side (below / behind the centre)";
  const cv::Size ns = text_size(note.text, 0.4, 1, &base);
  note.text_org = note.marker = cv::Point2d(l.map.x, y - 2.0);
  note.box = cv::Rect2d(l.map.x, y - 2.0 - ns.height, ns.width, ns.height + base);
  out.push_back(note);
  return out;
}

Eigen::Vector2d azimuth_polar_deg(const Eigen::Vector3d& eye, const Eigen::Vector3d& centre) {
  const Eigen::Vector3d d = eye - centre;
  double az = std::atan2(d.y(), d.x());
  if (az < 0) az += 2 * kPi;
  if (az >= 2 * kPi) az = 0;
  const double n = d.norm();
  const double polar = n > 0 ? std::acos(std::clamp(d.z() / n, -1.0, 1.0)) : 0.0;
  return Eigen::Vector2d(az * 180.0 / kPi, polar * 180.0 / kPi);
}

PlanFigureLayout plan_figure_layout(const PlanFigure& f) {
  PlanFigureLayout l;
  const int header = kTitleBlock + kLineStep * static_cast<int>(f.lines.size());
  const int py = header + kLabelBlock;
  l.size = cv::Size(kWidth, py + kPanel + kBottom);
  l.top = cv::Rect(20, py, kPanel, kPanel);
  l.side = cv::Rect(l.top.br().x + 30, py, kPanel, kPanel);
  l.map = cv::Rect(l.side.br().x + 60, py + kMapStrip, kMapW, kMapW / 2);
  l.colour_bar = cv::Rect(l.map.x, l.map.br().y + 72, kMapW, 14);
  l.centre = f.centre;
  cv::Rect2d legend;
  for (const LegendItem& it : legend_items(l, f)) legend = legend.empty() ? it.box : (legend | it.box);
  l.legend = cv::Rect(cv::Point(int(std::floor(legend.x)), int(std::floor(legend.y))),
                      cv::Point(int(std::ceil(legend.br().x)), int(std::ceil(legend.br().y))));
  l.size.height = std::max(l.size.height, l.legend.br().y + 4);

  double r = 0;
  for (const auto& c : f.candidates) r = std::max(r, (c.translation() - f.centre).norm());
  for (const auto& c : f.past_views) r = std::max(r, (c.translation() - f.centre).norm());
  if (!(r > 0) || !std::isfinite(r)) {
    r = 0;
    if (!f.bbox.isEmpty()) {
      for (int k = 0; k < 8; ++k) {
        r = std::max(r, (f.bbox.corner(static_cast<Eigen::AlignedBox3d::CornerType>(k)) -
                         f.centre).norm());
      }
    }
    if (!(r > 0) || !std::isfinite(r)) r = 1.0 / 1.1;
  }
  l.half_width_m = 1.1 * r;
  return l;
}

cv::Point2d top_view_pixel(const PlanFigureLayout& l, const Eigen::Vector3d& p) {
  return ortho_pixel(l, OrthoView{l.top, 0, 1, 2, 1.0}, p);
}

cv::Point2d side_view_pixel(const PlanFigureLayout& l, const Eigen::Vector3d& p) {
  return ortho_pixel(l, OrthoView{l.side, 0, 2, 1, -1.0}, p);
}

cv::Point2d sphere_map_pixel(const PlanFigureLayout& l, double azimuth_deg, double polar_deg) {
  return cv::Point2d(l.map.x + azimuth_deg / 360.0 * l.map.width,
                     l.map.y + polar_deg / 180.0 * l.map.height);
}

namespace {

cv::Mat draw_figure(const PlanFigure& f, Svg* svg) {
  validate(f);
  const PlanFigureLayout l = plan_figure_layout(f);
  cv::Mat fig(l.size, CV_8UC3, scalar(PlanFigureColours::background()));
  const FRange range = f_range(f);

  Canvas all(fig, cv::Rect(0, 0, fig.cols, fig.rows), kPixelCentre, svg);
  all.text(f.title, {20.0, 30.0}, 0.75, kBlack, 2);
  for (size_t i = 0; i < f.lines.size(); ++i) {
    all.text(f.lines[i], {22.0, 30.0 + kLineStep * (i + 1.0)}, 0.5, kText);
  }

  const OrthoView top{l.top, 0, 1, 2, 1.0};     // seen from above: larger z is nearer
  const OrthoView side{l.side, 0, 2, 1, -1.0};  // seen from -y: smaller y is nearer
  draw_ortho_panel(fig, svg, l, top, f, range, true);
  draw_ortho_panel(fig, svg, l, side, f, range, false);
  draw_map_panel(fig, svg, l, f, range);

  const double step = nice_step(2.0 * l.half_width_m);
  for (const auto* v : {&top, &side}) {
    all.rect({double(v->rect.x), double(v->rect.y)},
             {double(v->rect.br().x), double(v->rect.br().y)}, kFrame);
  }
  const std::string grid = ", grid " + metres(step);
  all.text("top view (x right, y up)" + grid, {double(l.top.x), l.top.y - 8.0}, 0.5, kText);
  all.text("side view (x right, z up)" + grid, {double(l.side.x), l.side.y - 8.0}, 0.5, kText);
  all.text("candidate sphere: azimuth vs polar angle from +z (deg)",
           {double(l.map.x) - 40.0, l.map.y - kMapStrip - 8.0}, 0.5, kText);
  if (f.chosen < 0) {
    all.text("no view chosen (stop)", {kWidth - 20.0, 30.0}, 0.75, cv::Scalar(0, 0, 200), 2, 2);
  }
  return fig;
}

}  // namespace

cv::Mat draw_plan_figure(const PlanFigure& f) { return draw_figure(f, nullptr); }

std::string plan_figure_svg(const PlanFigure& f) {
  const PlanFigureLayout l = plan_figure_layout(f);
  Svg svg(l.size.width, l.size.height);
  draw_figure(f, &svg);
  return svg.document();
}

void write_plan_figure(const PlanFigure& f, const std::string& path) {
  const PlanFigureLayout l = plan_figure_layout(f);
  Svg svg(l.size.width, l.size.height);
  const cv::Mat fig = draw_figure(f, &svg);
  const cv::Mat bgr = fig.isContinuous() ? fig : fig.clone();
  if (bgr.type() != CV_8UC3) throw std::logic_error("plan figure for '" + path + "' is not an 8-bit colour image");
  const std::vector<uint8_t> png = encode_png(bgr.data, bgr.cols, bgr.rows, PngPixels::kBgr8, 6, "plan figure " + path);
  write_file_atomic(path, std::string_view(reinterpret_cast<const char*>(png.data()), png.size()));
  drawing::write_text_file(drawing::svg_path_beside(path), svg.document(), "plan figure (SVG)");
}

PlanFigure plan_figure(const PlanInput& in, const PlanResult& r, const std::string& title) {
  PlanFigure f;
  f.title = title;
  f.ellipsoids = in.ellipsoids;
  f.candidates = r.candidates;
  f.status = r.status;
  f.quality.reserve(r.scores.size());
  for (const auto& s : r.scores) f.quality.push_back(s.quality);
  f.chosen = r.outcome == PlanResult::Outcome::kView ? r.chosen : -1;
  f.past_views = in.views_done;
  f.bbox = in.bbox;
  f.centre = r.centre;
  f.beta = in.beta;
  f.sector_start_rad = r.sector_start_rad;
  f.allowed_sectors = r.allowed_sectors;
  std::ostringstream a, b;
  a << r.num_occupied_ellipsoids << " occupied and " << r.num_frontier_ellipsoids << " frontier ellipsoids; "
    << r.candidates.size() << " candidates, " << r.num_unreachable << " unreachable, " << r.num_excluded
    << " excluded, " << r.num_scored << " scored";
  b << (r.outcome == PlanResult::Outcome::kView ? "chosen: " : r.outcome == PlanResult::Outcome::kStop ? "stop: " : "failed: ")
    << r.reason << (r.partition_fallback ? " (no candidate in the allowed sectors: chosen globally)" : "");
  f.lines = {a.str(), b.str()};
  return f;
}

}  // namespace pbnbv
