// The planning-step figure (plan_figure.hpp): layout, marker placement, PNG output, errors.
#include "report/plan_figure.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "file_test_util.hpp"
#include "core/mapping/state_colour.hpp"
#include "core/planning/view_scoring.hpp"
#include "core/base/units.hpp"
#include "sphere_ellipsoid.hpp"

namespace pbnbv {
namespace {

using testing::sphere_ellipsoid;


// One candidate at (1, 0, 0) looking at the origin, chosen; B = [-0.1, 0.1]^3; one frontier
// sphere of radius 0.1 at the origin; no partition.
PlanFigure one_candidate() {
  PlanFigure f;
  f.title = "test - view 1 of 1";
  f.lines = {"F = 1.0", "T = 1"};
  f.ellipsoids = {sphere_ellipsoid(Eigen::Vector3d::Zero(), 0.1, EllipsoidClass::kFrontier)};
  f.candidates = {look_at_z_up(Eigen::Vector3d(1, 0, 0), Eigen::Vector3d::Zero())};
  f.quality = {1.0};
  f.status = {CandidateStatus::kScored};
  f.chosen = 0;
  f.bbox = Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-0.1), Eigen::Vector3d::Constant(0.1));
  f.beta = 0;
  return f;
}

cv::Vec3b at(const cv::Mat& img, const cv::Point2d& p) {
  return img.at<cv::Vec3b>(static_cast<int>(std::floor(p.y)), static_cast<int>(std::floor(p.x)));
}

// Channels within `tol` of each other.
void expect_colour(const cv::Vec3b& got, const cv::Vec3b& want, int tol, const char* what) {
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(got[c], want[c], tol) << what << ": got " << got << ", want " << want;
  }
}

TEST(PlanFigure, SizeAndLayout) {
  const PlanFigure f = one_candidate();
  const cv::Mat img = draw_plan_figure(f);
  const PlanFigureLayout l = plan_figure_layout(f);
  EXPECT_EQ(img.type(), CV_8UC3);
  EXPECT_EQ(img.cols, 1500);
  EXPECT_EQ(img.rows, 560);  // 520 + 20 per text line, two lines
  EXPECT_EQ(img.size(), l.size);
  // Panels inside the figure and apart.
  const cv::Rect all(0, 0, img.cols, img.rows);
  for (const cv::Rect& r : {l.top, l.side, l.map, l.colour_bar}) EXPECT_EQ(r & all, r);
  EXPECT_EQ(l.top.width, l.top.height);
  EXPECT_EQ(l.map.width, 2 * l.map.height);
  EXPECT_TRUE((l.top & l.side).empty());
  EXPECT_TRUE((l.side & l.map).empty());
  // Half-width: 1.1 x the farthest candidate (1 m).
  EXPECT_NEAR(l.half_width_m, 1.1, 1e-12);
  // More text lines make the figure taller by 20 px each.
  PlanFigure g = f;
  g.lines.push_back("third line");
  EXPECT_EQ(draw_plan_figure(g).rows, 580);
}

TEST(PlanFigure, PixelMapping) {
  const PlanFigureLayout l = plan_figure_layout(one_candidate());
  // Top view: centre at the middle of the panel, x right, y up; 220 px per 1.1 m.
  const cv::Point2d o = top_view_pixel(l, Eigen::Vector3d::Zero());
  EXPECT_DOUBLE_EQ(o.x, l.top.x + l.top.width / 2.0);
  EXPECT_DOUBLE_EQ(o.y, l.top.y + l.top.height / 2.0);
  const cv::Point2d e = top_view_pixel(l, Eigen::Vector3d(1, 0, 0));
  EXPECT_NEAR(e.x - o.x, 200.0, 1e-9);
  EXPECT_NEAR(e.y - o.y, 0.0, 1e-9);
  const cv::Point2d y = top_view_pixel(l, Eigen::Vector3d(0, 0.55, 0.3));
  EXPECT_NEAR(y.x - o.x, 0.0, 1e-9);
  EXPECT_NEAR(y.y - o.y, -110.0, 1e-9);
  // Side view: z up.
  const cv::Point2d s0 = side_view_pixel(l, Eigen::Vector3d::Zero());
  const cv::Point2d sz = side_view_pixel(l, Eigen::Vector3d(0, 0.4, 0.55));
  EXPECT_NEAR(sz.x - s0.x, 0.0, 1e-9);
  EXPECT_NEAR(sz.y - s0.y, -110.0, 1e-9);
  // Sphere map: azimuth 90, polar 90 is a quarter across and half down.
  const cv::Point2d m = sphere_map_pixel(l, 90, 90);
  EXPECT_DOUBLE_EQ(m.x, l.map.x + l.map.width / 4.0);
  EXPECT_DOUBLE_EQ(m.y, l.map.y + l.map.height / 2.0);
  const Eigen::Vector2d ap = azimuth_polar_deg(Eigen::Vector3d(0, 2, 0), Eigen::Vector3d::Zero());
  EXPECT_NEAR(ap(0), 90.0, 1e-12);
  EXPECT_NEAR(ap(1), 90.0, 1e-12);
  const Eigen::Vector2d up = azimuth_polar_deg(Eigen::Vector3d(0, -1, 1), Eigen::Vector3d::Zero());
  EXPECT_NEAR(up(0), 270.0, 1e-12);
  EXPECT_NEAR(up(1), 45.0, 1e-12);
}

TEST(PlanFigure, ChosenMarkerAndEllipsoidInTopView) {
  const PlanFigure f = one_candidate();
  const cv::Mat img = draw_plan_figure(f);
  const PlanFigureLayout l = plan_figure_layout(f);
  // The chosen marker sits at the candidate's eye (1, 0, 0).
  expect_colour(at(img, top_view_pixel(l, Eigen::Vector3d(1, 0, 0))), PlanFigureColours::chosen(),
                0, "chosen marker, top view");
  expect_colour(at(img, side_view_pixel(l, Eigen::Vector3d(1, 0, 0))),
                PlanFigureColours::chosen(), 0, "chosen marker, side view");
  // The world origin is inside the frontier ellipsoid's shadow: not background.
  EXPECT_NE(at(img, top_view_pixel(l, Eigen::Vector3d::Zero())), PlanFigureColours::background());
  // Off the line to the centre, still inside the shadow (radius 0.1 m = 20 px): the translucent
  // frontier fill over the white background.
  const double a = PlanFigureColours::fill_alpha();
  cv::Vec3b fill;
  for (int c = 0; c < 3; ++c) {
    fill[c] = cv::saturate_cast<uchar>(a * PlanFigureColours::frontier()[c] +
                                       (1 - a) * PlanFigureColours::background()[c]);
  }
  expect_colour(at(img, top_view_pixel(l, Eigen::Vector3d(-0.03, 0.05, 0))), fill, 2,
                "frontier fill, top view");
  expect_colour(at(img, side_view_pixel(l, Eigen::Vector3d(-0.03, 0, -0.05))), fill, 2,
                "frontier fill, side view");
  // Outside the shadow and B, away from the markers: background.
  expect_colour(at(img, top_view_pixel(l, Eigen::Vector3d(-0.45, 0.33, 0))),
                PlanFigureColours::background(), 0, "background");
}

TEST(PlanFigure, EllipsoidShadowFollowsOrientation) {
  // A needle along the world diagonal x = y (semi-axis 0.5), thin otherwise: its top-view shadow
  // covers (0.3, 0.3) but not (0.3, -0.3).
  PlanFigure f = one_candidate();
  Ellipsoid e;
  e.cls = EllipsoidClass::kOccupied;
  e.axes = Eigen::AngleAxisd(kPi / 4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  e.semi_axes = Eigen::Vector3d(0.5, 0.03, 0.03);
  f.ellipsoids = {e};
  f.bbox = Eigen::AlignedBox3d();  // empty: not drawn
  const cv::Mat img = draw_plan_figure(f);
  const PlanFigureLayout l = plan_figure_layout(f);
  EXPECT_NE(at(img, top_view_pixel(l, Eigen::Vector3d(0.3, 0.3, 0))),
            PlanFigureColours::background());
  EXPECT_EQ(at(img, top_view_pixel(l, Eigen::Vector3d(0.3, -0.3, 0))),
            PlanFigureColours::background());
  // Side view (x, z): the shadow spans x in about [-0.35, 0.35] and is thin in z.
  EXPECT_NE(at(img, side_view_pixel(l, Eigen::Vector3d(-0.3, 0, 0))),
            PlanFigureColours::background());
  EXPECT_EQ(at(img, side_view_pixel(l, Eigen::Vector3d(-0.3, 0, 0.2))),
            PlanFigureColours::background());
}

// The ellipsoids are drawn in their voxel state's colour from the one palette that the map's
// .ot file uses (core/mapping/state_colour.hpp): frontier orange, occupied blue.
TEST(PlanFigure, EllipsoidsTakeTheMapPalette) {
  PlanFigure f = one_candidate();
  f.ellipsoids = {sphere_ellipsoid(Eigen::Vector3d(-0.3, 0.3, 0), 0.1, EllipsoidClass::kFrontier),
                  sphere_ellipsoid(Eigen::Vector3d(0.3, -0.3, 0), 0.1, EllipsoidClass::kOccupied)};
  const cv::Mat img = draw_plan_figure(f);
  const PlanFigureLayout l = plan_figure_layout(f);
  // The palette's RGB as BGR: orange (255, 140, 40) and blue (40, 110, 230).
  EXPECT_EQ(PlanFigureColours::frontier(), cv::Vec3b(40, 140, 255));
  EXPECT_EQ(PlanFigureColours::occupied(), cv::Vec3b(230, 110, 40));
  EXPECT_EQ(PlanFigureColours::frontier(), to_bgr(state_colour(VoxelState::kFrontier)));
  EXPECT_EQ(PlanFigureColours::occupied(), to_bgr(state_colour(VoxelState::kOccupied)));
  // Inside each shadow, off the grid lines and the outlines: the translucent fill of that colour
  // over the white background.
  const double a = PlanFigureColours::fill_alpha();
  auto fill = [&](VoxelState s) {
    const Rgb c = state_colour(s);
    const double bgr[3] = {double(c.b), double(c.g), double(c.r)};
    cv::Vec3b v;
    for (int i = 0; i < 3; ++i) v[i] = cv::saturate_cast<uchar>(a * bgr[i] + (1 - a) * 255.0);
    return v;
  };
  expect_colour(at(img, top_view_pixel(l, Eigen::Vector3d(-0.33, 0.27, 0))),
                fill(VoxelState::kFrontier), 2, "frontier fill");
  expect_colour(at(img, top_view_pixel(l, Eigen::Vector3d(0.27, -0.33, 0))),
                fill(VoxelState::kOccupied), 2, "occupied fill");
}

TEST(PlanFigure, MapPanelPlacesCandidateByAzimuthAndPolarAngle) {
  PlanFigure f = one_candidate();
  f.candidates = {look_at_z_up(Eigen::Vector3d(0, 1, 0), Eigen::Vector3d::Zero())};
  const cv::Mat img = draw_plan_figure(f);
  const PlanFigureLayout l = plan_figure_layout(f);
  const cv::Point2d p(l.map.x + l.map.width / 4.0, l.map.y + l.map.height / 2.0);
  expect_colour(at(img, p), PlanFigureColours::chosen(), 0, "chosen marker, map");
  // Not chosen: the dot has the colour-map colour, not the background.
  f.chosen = -1;
  const cv::Mat img2 = draw_plan_figure(f);
  const cv::Vec3b dot = at(img2, p);
  EXPECT_NE(dot, PlanFigureColours::background());
  EXPECT_NE(dot, PlanFigureColours::chosen());
  // Half a panel away (azimuth 270) nothing is drawn at the equator but the grid.
  const cv::Vec3b empty = at(img2, sphere_map_pixel(l, 270 - 20, 90 - 10));
  EXPECT_EQ(empty, PlanFigureColours::background());
}

TEST(PlanFigure, PartitionShadesAllowedSectorsOnly) {
  PlanFigure f = one_candidate();
  f.beta = 4;
  f.allowed_sectors = {1};  // azimuth 90..180: upper left quadrant of the top view
  const cv::Mat img = draw_plan_figure(f);
  const PlanFigureLayout l = plan_figure_layout(f);
  EXPECT_NE(at(img, top_view_pixel(l, Eigen::Vector3d(-0.45, 0.33, 0))),
            PlanFigureColours::background());
  EXPECT_EQ(at(img, top_view_pixel(l, Eigen::Vector3d(-0.45, -0.33, 0))),
            PlanFigureColours::background());
  EXPECT_NE(at(img, sphere_map_pixel(l, 130, 100)), PlanFigureColours::background());
  EXPECT_EQ(at(img, sphere_map_pixel(l, 220, 100)), PlanFigureColours::background());
}

TEST(PlanFigure, PastViewsAreWhiteDiscs) {
  PlanFigure f = one_candidate();
  f.past_views = {look_at_z_up(Eigen::Vector3d(-0.9, 0.9, 0.2), Eigen::Vector3d::Zero())};
  const cv::Mat img = draw_plan_figure(f);
  const PlanFigureLayout l = plan_figure_layout(f);
  // The past view is farther from the centre than the candidate and sets the scale.
  EXPECT_NEAR(l.half_width_m, 1.1 * std::sqrt(1.66), 1e-12);
  // The disc's ring is black; a pixel between the number and the ring is white.
  const cv::Point2d c = top_view_pixel(l, f.past_views[0].translation());
  EXPECT_EQ(at(img, c + cv::Point2d(0, -7)), PlanFigureColours::past_view());
  EXPECT_LT(int(at(img, c + cv::Point2d(0, -9))[0]), 128);
}

class PlanFigureFile : public testing::TempDirTest {};

TEST_F(PlanFigureFile, WritesPngThatReadsBack) {
  const PlanFigure f = one_candidate();
  const std::string p = path("step.png");
  write_plan_figure(f, p);
  const cv::Mat back = cv::imread(p, cv::IMREAD_COLOR);
  ASSERT_FALSE(back.empty());
  EXPECT_EQ(back.size(), draw_plan_figure(f).size());
  // Lossless: the same pixels.
  EXPECT_EQ(cv::norm(back, draw_plan_figure(f), cv::NORM_INF), 0.0);
  // PNG whatever the name says.
  const std::string q = path("step.figure");
  write_plan_figure(f, q);
  EXPECT_EQ(cv::imread(q, cv::IMREAD_COLOR).size(), back.size());
}

// The SVG beside the PNG: same size, the title, the chosen marker's disc at the chosen
// candidate's top-view pixel in the chosen colour.
TEST_F(PlanFigureFile, WritesSvgBesidePng) {
  const PlanFigure f = one_candidate();
  write_plan_figure(f, path("step.png"));
  std::ifstream in(path("step.svg"));
  std::ostringstream ss;
  ss << in.rdbuf();
  const std::string svg = ss.str();
  EXPECT_EQ(svg, plan_figure_svg(f));
  EXPECT_NE(svg.find("width=\"1500\" height=\"560\""), std::string::npos);
  EXPECT_NE(svg.find(">test - view 1 of 1</text>"), std::string::npos);
  const cv::Point2d p = top_view_pixel(plan_figure_layout(f), Eigen::Vector3d(1, 0, 0));
  char disc[160];
  std::snprintf(disc, sizeof(disc), "cx=\"%.2f\" cy=\"%.2f\" r=\"8.00\" fill=\"#dc1ec8\"/>", p.x, p.y);
  EXPECT_NE(svg.find(disc), std::string::npos) << disc;
}

TEST_F(PlanFigureFile, UnwritablePathThrowsNamingIt) {
  const std::string p = path("no/such/dir/step.png");
  testing::expect_error([&] { write_plan_figure(one_candidate(), p); }, {p});
}

void expect_invalid(const PlanFigure& f, const std::string& field) {
  try {
    draw_plan_figure(f);
    ADD_FAILURE() << "no exception for " << field;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
  }
  EXPECT_THROW(write_plan_figure(f, "/tmp/never_written_plan_figure.png"), std::invalid_argument);
}

TEST(PlanFigure, MismatchedSizesAndBadChosenThrow) {
  PlanFigure f = one_candidate();
  f.quality.push_back(2.0);
  expect_invalid(f, "quality");
  f = one_candidate();
  f.status.clear();
  expect_invalid(f, "status");
  f = one_candidate();
  f.chosen = 1;
  expect_invalid(f, "chosen");
  f.chosen = -2;
  expect_invalid(f, "chosen");
}

TEST(PlanFigure, EmptyAndDegenerateInputsDraw) {
  PlanFigure f;  // nothing at all
  f.chosen = -1;
  cv::Mat img;
  EXPECT_NO_THROW(img = draw_plan_figure(f));
  EXPECT_EQ(img.cols, 1500);
  // All candidates unreachable or outside: no F range, still draws.
  f = one_candidate();
  f.status = {CandidateStatus::kUnreachable};
  f.chosen = -1;
  EXPECT_NO_THROW(draw_plan_figure(f));
  // A flat (zero-thickness) ellipsoid and a non-finite F.
  f = one_candidate();
  f.ellipsoids[0].semi_axes = Eigen::Vector3d(0.2, 0.1, 0.0);
  f.quality = {std::nan("")};
  EXPECT_NO_THROW(draw_plan_figure(f));
}

// A realistic step: 800 candidates on a Fibonacci sphere scored by score_view against a few
// ellipsoids, three past views, a 4-sector partition. Always drawn; written when
// PBNBV_PLAN_FIGURE_SAMPLE names a file.
PlanFigure realistic_step() {
  PlanFigure f;
  f.title = "bunny - view 4 of 10 - pbnbv";
  f.centre = Eigen::Vector3d(0, 0, 0.05);
  f.bbox = Eigen::AlignedBox3d(Eigen::Vector3d(-0.16, -0.12, -0.08),
                               Eigen::Vector3d(0.16, 0.12, 0.2));
  auto ell = [](EllipsoidClass cls, Eigen::Vector3d c, double yaw, double pitch,
                Eigen::Vector3d s) {
    Ellipsoid e;
    e.cls = cls;
    e.centre = c;
    e.axes = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
              Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()))
                 .toRotationMatrix();
    e.semi_axes = s;
    return e;
  };
  using EC = EllipsoidClass;
  f.ellipsoids = {
      ell(EC::kOccupied, {0.02, 0.0, 0.0}, 0.3, 0.0, {0.13, 0.09, 0.08}),
      ell(EC::kOccupied, {-0.09, 0.03, 0.1}, -0.4, 0.5, {0.07, 0.05, 0.06}),
      ell(EC::kOccupied, {-0.11, 0.06, 0.17}, 0.2, 1.2, {0.05, 0.015, 0.025}),
      ell(EC::kFrontier, {0.05, -0.1, 0.02}, 0.2, 0.0, {0.09, 0.025, 0.07}),
      ell(EC::kFrontier, {0.12, 0.05, -0.04}, 1.3, 0.2, {0.06, 0.02, 0.04}),
      ell(EC::kFrontier, {-0.05, -0.04, 0.16}, 0.0, 0.0, {0.06, 0.05, 0.02}),
  };
  CameraIntrinsics k;
  k.width = 320;
  k.height = 180;
  k.fx = k.fy = 174;
  k.cx = 160;
  k.cy = 90;
  const double radius = 0.6;
  f.beta = 4;
  std::vector<bool> scanned(4, false);
  const std::vector<Eigen::Vector2d> past = {{20, 60}, {75, 80}, {160, 50}};  // az, polar deg
  for (const auto& ap : past) {
    const double az = ap(0) * kPi / 180, po = ap(1) * kPi / 180;
    const Eigen::Vector3d eye =
        f.centre + radius * Eigen::Vector3d(std::sin(po) * std::cos(az),
                                            std::sin(po) * std::sin(az), std::cos(po));
    f.past_views.push_back(look_at_z_up(eye, f.centre));
    scanned[sector_of(eye, f.centre, f.beta)] = true;
  }
  f.allowed_sectors = allowed_sectors(scanned);
  const int n = 800;
  const double golden = kPi * (3 - std::sqrt(5.0));
  double best = -1e300;
  for (int i = 0; i < n; ++i) {
    const double z = 1 - 2 * (i + 0.5) / n;
    const double rxy = std::sqrt(1 - z * z);
    const Eigen::Vector3d eye = f.centre + radius * Eigen::Vector3d(rxy * std::cos(golden * i),
                                                                    rxy * std::sin(golden * i), z);
    const Pose pose = look_at_z_up(eye, f.centre);
    f.candidates.push_back(pose);
    const double q = score_view(f.ellipsoids, k, pose).quality;
    f.quality.push_back(q);
    CandidateStatus st = CandidateStatus::kScored;
    const int s = sector_of(eye, f.centre, f.beta);
    if (eye.z() < -0.1) {
      st = CandidateStatus::kUnreachable;  // below the table
    } else if (std::find(f.allowed_sectors.begin(), f.allowed_sectors.end(), s) ==
               f.allowed_sectors.end()) {
      st = CandidateStatus::kOutsidePartition;
    }
    f.status.push_back(st);
    if (st == CandidateStatus::kScored && q > best) {
      best = q;
      f.chosen = i;
    }
  }
  char buf[200];
  std::snprintf(buf, sizeof(buf),
                "chosen: candidate %d, F = %.4g (frontier minus occupied projected area, px); "
                "T = 3 occupied + 3 frontier ellipsoids",
                f.chosen, best);
  std::string allowed;
  for (int s : f.allowed_sectors) allowed += (allowed.empty() ? "s" : ", s") + std::to_string(s);
  f.lines = {buf, "800 candidates on a sphere of r = 0.6 m; beta = 4, allowed sectors " + allowed +
                      "; timings: ellipsoids 41 ms, scoring 18 ms"};
  return f;
}

// Every legend entry lies inside the figure (12 px clear of the right edge), none overlaps
// another, and the last one is drawn: with a partition and an excluded candidate the second row
// wraps.
TEST(PlanFigure, LegendLiesInsideTheFigure) {
  PlanFigure f = realistic_step();
  f.status[0] = CandidateStatus::kExcluded;
  const PlanFigureLayout l = plan_figure_layout(f);
  const cv::Mat img = draw_plan_figure(f);
  const std::vector<LegendItem> items = legend_items(l, f);
  ASSERT_EQ(items.size(), 9u);  // 4 + 4 + the note
  const cv::Rect2d inside(0, 0, img.cols - 12, img.rows);
  for (size_t i = 0; i < items.size(); ++i) {
    EXPECT_EQ(items[i].box & inside, items[i].box) << items[i].text;
    EXPECT_EQ(cv::Rect2d(l.legend) & items[i].box, items[i].box) << items[i].text;
    for (size_t j = 0; j < i; ++j) {
      EXPECT_LE((items[i].box & items[j].box).area(), 0.0) << items[i].text << " / " << items[j].text;
    }
  }
  EXPECT_EQ(l.legend & cv::Rect(0, 0, img.cols, img.rows), l.legend);
  EXPECT_EQ(items[7].text, "excluded");
  EXPECT_GT(items[7].box.y, items[4].box.y);  // wrapped onto its own row
  // The excluded cross is drawn at its marker (red ink, not background).
  expect_colour(at(img, items[7].marker), cv::Vec3b(30, 30, 210), 60, "excluded legend cross");
}

// A view at azimuth 0 is drawn at both edges of the sphere map, whole: the chosen marker's
// magenta disc (radius 8) shows just inside the left edge and just inside the right edge, and a
// past view's black ring (radius 9) likewise.
TEST(PlanFigure, ViewAtAzimuthZeroIsDrawnAtBothEdges) {
  PlanFigure f = one_candidate();  // chosen at (1, 0, 0): azimuth 0, polar 90
  f.past_views = {look_at_z_up(Eigen::Vector3d(0.5, 0, 0.5 * std::sqrt(3.0)), Eigen::Vector3d::Zero())};  // polar 30
  const PlanFigureLayout l = plan_figure_layout(f);
  const cv::Mat img = draw_plan_figure(f);
  const cv::Point2d left = sphere_map_pixel(l, 0, 90), right = sphere_map_pixel(l, 360, 90);
  expect_colour(at(img, left + cv::Point2d(3, 0)), PlanFigureColours::chosen(), 0, "chosen, left edge");
  expect_colour(at(img, right + cv::Point2d(-4, 0)), PlanFigureColours::chosen(), 0, "chosen, right edge");
  const cv::Point2d pl = sphere_map_pixel(l, 0, 30), pr = sphere_map_pixel(l, 360, 30);
  EXPECT_LT(int(at(img, pl + cv::Point2d(9, 0))[0]), 128) << "past view ring, left";
  EXPECT_LT(int(at(img, pr + cv::Point2d(-9, 0))[0]), 128) << "past view ring, right";
  EXPECT_EQ(at(img, pr + cv::Point2d(-5, 0)), PlanFigureColours::past_view()) << "past view disc, right";
}

// Sector names: one per sector in the top view and one over the map, inside their panel, clear of
// every marker (candidates, past views, chosen), and drawn over everything (the box's corner
// has the sector's background colour).
TEST(PlanFigure, SectorLabelsKeepClearOfMarkers) {
  const PlanFigure f = realistic_step();
  const PlanFigureLayout l = plan_figure_layout(f);
  const cv::Mat img = draw_plan_figure(f);
  const std::vector<SectorLabel> labels = sector_labels(l, f);
  ASSERT_EQ(labels.size(), 8u);
  auto clear = [](const cv::Rect2d& b, const cv::Point2d& p, double r) {
    const double dx = std::max({b.x - p.x, p.x - b.br().x, 0.0}), dy = std::max({b.y - p.y, p.y - b.br().y, 0.0});
    return dx * dx + dy * dy >= r * r;
  };
  for (const SectorLabel& s : labels) {
    // Panel 3's names sit in the 18-px strip above the map.
    const cv::Rect2d panel = s.in_top ? cv::Rect2d(l.top) : cv::Rect2d(l.map.x, l.map.y - 18, l.map.width, 18);
    EXPECT_EQ(s.box & panel, s.box) << s.text;
    for (size_t i = 0; i < f.candidates.size(); ++i) {
      const Eigen::Vector3d e = f.candidates[i].translation();
      const Eigen::Vector2d ap = azimuth_polar_deg(e, f.centre);
      const cv::Point2d p = s.in_top ? top_view_pixel(l, e) : sphere_map_pixel(l, ap(0), ap(1));
      EXPECT_TRUE(clear(s.box, p, 3.6)) << s.text << (s.in_top ? " (top)" : " (map)") << " covers candidate " << i;
    }
    for (const Pose& v : f.past_views) {
      const Eigen::Vector2d ap = azimuth_polar_deg(v.translation(), f.centre);
      const cv::Point2d p = s.in_top ? top_view_pixel(l, v.translation()) : sphere_map_pixel(l, ap(0), ap(1));
      EXPECT_TRUE(clear(s.box, p, 10.0)) << s.text << " covers a past view";
    }
    const bool allowed = std::count(f.allowed_sectors.begin(), f.allowed_sectors.end(), s.sector) > 0;
    const cv::Vec3b bg = allowed ? cv::Vec3b(228, 246, 230) : PlanFigureColours::background();
    expect_colour(at(img, s.box.tl() + cv::Point2d(1.5, 1.5)), bg, 0, "label box corner");
  }
}

TEST(PlanFigure, RealisticStep) {
  const PlanFigure f = realistic_step();
  const cv::Mat img = draw_plan_figure(f);
  EXPECT_EQ(img.size(), plan_figure_layout(f).size);
  ASSERT_GE(f.chosen, 0);
  const PlanFigureLayout l = plan_figure_layout(f);
  expect_colour(at(img, top_view_pixel(l, f.candidates[f.chosen].translation())),
                PlanFigureColours::chosen(), 0, "chosen, realistic");
  if (const char* out = std::getenv("PBNBV_PLAN_FIGURE_SAMPLE")) {
    write_plan_figure(f, out);
    PlanFigure stop = f;  // the same step as a stop, next to it
    stop.chosen = -1;
    write_plan_figure(stop, std::string(out) + ".stop.png");
  }
}

}  // namespace
}  // namespace pbnbv
