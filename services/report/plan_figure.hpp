#pragma once
// A picture of one planning step: the ellipsoids, every candidate view coloured by its quality F,
// the views taken so far, the global partition and the chosen view, so a person can see why a
// view was chosen. Drawn with OpenCV (core, imgproc), written as PNG by libpng (core/io/image_codec.hpp).
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "core/mapping/state_colour.hpp"
#include "core/planning/ellipsoid.hpp"
#include "core/planning/planner.hpp"
#include "core/base/pose.hpp"

namespace pbnbv {


struct PlanFigure {
  std::string title;                         // e.g. "bunny - view 3 of 10 - pbnbv"
  std::vector<Ellipsoid> ellipsoids;
  std::vector<Pose> candidates;              // object_T_camera of every candidate
  std::vector<double> quality;               // F per candidate (ignored unless kScored)
  std::vector<CandidateStatus> status;       // per candidate
  int chosen = -1;                           // index into candidates, -1: none (stop)
  std::vector<Pose> past_views;              // camera poses of the views taken so far
  Eigen::AlignedBox3d bbox;                  // bounding box B (empty: not drawn)
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // centre of the candidate sphere
  int beta = kSectors.value;                 // partition sectors (0 or 1: no partition lines)
  double sector_start_rad = 0;               // azimuth where sector 0 starts
  std::vector<int> allowed_sectors;          // sectors the choice was allowed from
  std::vector<std::string> lines;            // text lines printed under the title (F, T, timings)
  std::string quality_label = "view quality F of the scored candidates";  // the colour bar's
};

// Draws the figure (BGR 8-bit, 1500 px wide, 520 + 20 per text line high, 560 with two lines;
// taller when the legend needs more rows):
// a header (title, then `lines`) above three panels
//  1. top view (x right, y up, orthographic) and 2. side view (x right, z up), each a square
//     world region centred on `centre` with half-width 1.1 x the largest distance of a candidate
//     or past view from `centre`: B, the ellipsoids' shadow outlines (occupied blue, frontier
//     orange: the map's palette; filled translucent), candidate camera centres coloured by F
//     (viridis; unreachable: small black cross; outside the partition: small grey dot;
//     excluded: small red cross; candidates on the far half, below the centre in the top view /
//     behind it in the side view, drawn paler),
//     past views as numbered white circles, the chosen view as a large magenta marker with a
//     line to `centre`; in the top view, the sector boundaries with the allowed sectors shaded;
//  3. a map of the candidate sphere, azimuth about `centre` (0..360 deg, x) against the polar
//     angle from +z (0..180 deg, y), with the same markers (those at the 0/360 deg edges drawn
//     at both edges), and a colour bar of F over the scored candidates (min..max);
// sector names where no marker is (sector_labels) and a legend within the width (legend_items).
// Throws std::invalid_argument naming the field when quality or status differ in size from
// candidates or chosen is out of range.
cv::Mat draw_plan_figure(const PlanFigure& f);

// The same figure as an SVG document (one user unit per figure pixel).
std::string plan_figure_svg(const PlanFigure& f);

// Draws and writes the figure as PNG, and as SVG beside it (path with the extension ".svg").
// Throws std::invalid_argument as draw_plan_figure, and
// std::runtime_error naming the path when the file cannot be written.
void write_plan_figure(const PlanFigure& f, const std::string& path);

// --- Layout helpers (exposed for tests and for placing annotations) ---

struct PlanFigureLayout {
  cv::Size size;              // whole figure
  cv::Rect top;               // panel 1 (square)
  cv::Rect side;              // panel 2 (square, same size)
  cv::Rect map;               // panel 3 (2:1, azimuth 0..360 x polar 0..180)
  cv::Rect colour_bar;
  cv::Rect legend;            // bounding box of the legend under the colour bar (wraps into rows
                              // within the figure's width; the figure grows to hold them)
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double half_width_m = 1.0;  // world half-width shown by panels 1 and 2
};

PlanFigureLayout plan_figure_layout(const PlanFigure& f);

// A sector's name ("s0", ...) on a box centred on `centre`, drawn over everything: in panel 1
// (in_top) where it covers no marker (candidates, past views, the chosen view) if such a spot
// exists just outside the ring of camera centres or along the sector's middle, else where it
// covers fewest; for panel 3, in an 18-px strip above the map over the sector's middle azimuth.
struct SectorLabel {
  int sector = 0;
  bool in_top = true;
  std::string text;
  cv::Point2d centre;
  cv::Rect2d box;
};
std::vector<SectorLabel> sector_labels(const PlanFigureLayout& l, const PlanFigure& f);

// The legend's items under the colour bar, in rows that wrap within the figure's width.
enum class LegendKind { kChosen, kPast, kUnreachable, kOutside, kOccupied, kFrontier, kAllowed, kExcluded, kNote };
struct LegendItem {
  LegendKind kind;
  std::string text;
  cv::Point2d marker, text_org;  // marker centre; text baseline start
  cv::Rect2d box;                // marker and text
};
std::vector<LegendItem> legend_items(const PlanFigureLayout& l, const PlanFigure& f);

// Figure pixel coordinates (x right, y down; pixel (i, j) covers [i, i+1) x [j, j+1), so a
// point's pixel is (floor(x), floor(y))) of a world point in panel 1 (its x, y) and panel 2
// (its x, z).
cv::Point2d top_view_pixel(const PlanFigureLayout& l, const Eigen::Vector3d& p);
cv::Point2d side_view_pixel(const PlanFigureLayout& l, const Eigen::Vector3d& p);
// Figure pixel coordinates of (azimuth, polar) in degrees in panel 3.
cv::Point2d sphere_map_pixel(const PlanFigureLayout& l, double azimuth_deg, double polar_deg);
// Azimuth in [0, 360) about centre (as sector_of) and polar angle from +z in [0, 180], degrees.
Eigen::Vector2d azimuth_polar_deg(const Eigen::Vector3d& eye, const Eigen::Vector3d& centre);

// An RGB colour of the voxel palette as OpenCV's BGR.
inline cv::Vec3b to_bgr(const Rgb& c) { return {c.b, c.g, c.r}; }

// Colours (BGR) the tests look for. The ellipsoids take their voxel state's colour from the one
// palette (state_colour.hpp), so a frontier is the same orange here as in the map's .ot file.
struct PlanFigureColours {
  static cv::Vec3b background() { return {255, 255, 255}; }
  static cv::Vec3b chosen() { return {200, 30, 220}; }     // magenta
  static cv::Vec3b frontier() { return to_bgr(state_colour(VoxelState::kFrontier)); }  // orange
  static cv::Vec3b occupied() { return to_bgr(state_colour(VoxelState::kOccupied)); }  // blue
  static cv::Vec3b past_view() { return {255, 255, 255}; }  // white disc, black ring and number
  static double fill_alpha() { return 0.35; }               // ellipsoid fill opacity
};

// The figure of a planning step (plan_figure.hpp) with the result's candidates and scores.
PlanFigure plan_figure(const PlanInput& in, const PlanResult& r, const std::string& title);

}  // namespace pbnbv
