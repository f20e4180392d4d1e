// The surface stop rule on hand-made per-view curves, and the new-surface figure on planes whose
// answer is known by hand.
#include "core/scan/stop_rule.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace pbnbv;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A square of points on a 2 mm grid, x in [x0, x0 + 0.1], y in [0, 0.1], at height z: 51 x 51.
PointCloud plane(float x0, float z) {
  PointCloud p;
  for (int i = 0; i <= 50; ++i)
    for (int j = 0; j <= 50; ++j) p.emplace_back(x0 + 0.002f * i, 0.002f * j, z);
  return p;
}

SurfaceStopRule rule(int window, double percent, int min_views) {
  SurfaceStopRule r;
  r.window = window;
  r.max_new_percent = percent;
  r.min_views = min_views;
  return r;
}

}  // namespace

TEST(StopRule, DecayingCurveStopsAfterTheWindowOfSmallViews) {
  const std::vector<double> curve{100, 60, 20, 3, 1, 0.4, 0.3, 0.2, 0.1};
  // Below 0.5 %: views 6 and 7 are the first two in a row -> stop after view 7.
  auto d = first_surface_stop(curve, rule(2, 0.5, 3));
  ASSERT_TRUE(d);
  EXPECT_EQ(d->after_views, 7);
  EXPECT_EQ(d->last_percent, (std::vector<double>{0.4, 0.3}));
  EXPECT_EQ(d->reason, "views 6-7 each added less than 0.50 % new surface (0.40, 0.30 % of the model)");
  // Below 2 %: views 5 (1 %) and 6 (0.4 %) -> after view 6; one view below 5 %: view 4 (3 %).
  EXPECT_EQ(first_surface_stop(curve, rule(2, 2.0, 3))->after_views, 6);
  EXPECT_EQ(first_surface_stop(curve, rule(1, 5.0, 3))->after_views, 4);
  // Nothing below 0.05 %: never.
  EXPECT_FALSE(first_surface_stop(curve, rule(2, 0.05, 3)));
  // The decision on the whole curve so far is the same as on its prefix at the stop.
  EXPECT_TRUE(surface_stop({100, 60, 20, 3, 1, 0.4, 0.3}, rule(2, 0.5, 3)));
  EXPECT_FALSE(surface_stop({100, 60, 20, 3, 1, 0.4}, rule(2, 0.5, 3)));
}

TEST(StopRule, LateJumpInsideTheWindowIsNotStoppedBefore) {
  // Views 3 and 5 add little, view 4 a lot (a side seen for the first time).
  const std::vector<double> curve{100, 50, 0.2, 5, 0.1, 0.1};
  // A window of 2 sees view 4's jump next to views 3 and 5: the first two small views in a row
  // are 5 and 6.
  EXPECT_EQ(first_surface_stop(curve, rule(2, 0.5, 1))->after_views, 6);
  // A window of 1 stops at view 3, before the jump.
  EXPECT_EQ(first_surface_stop(curve, rule(1, 0.5, 1))->after_views, 3);
  // A window of 3 covers the jump at every point of the curve: never.
  EXPECT_FALSE(first_surface_stop(curve, rule(3, 0.5, 1)));
}

TEST(StopRule, MinimumViewsRespected) {
  const std::vector<double> curve{100, 0.1, 0.1, 0.1, 0.1};
  EXPECT_EQ(first_surface_stop(curve, rule(2, 0.5, 1))->after_views, 3);
  EXPECT_EQ(first_surface_stop(curve, rule(2, 0.5, 4))->after_views, 4);
  EXPECT_FALSE(first_surface_stop(curve, rule(2, 0.5, 6)));
  EXPECT_FALSE(surface_stop({}, rule(1, 0.5, 1)));
}

TEST(StopRule, ViewsNotMergedNeitherCountNorBreakTheWindow) {
  // View 3 was rejected by the registration (no figure): views 2 and 4 are the window.
  const auto d = first_surface_stop({100, 0.1, kNaN, 0.2}, rule(2, 0.5, 1));
  ASSERT_TRUE(d);
  EXPECT_EQ(d->after_views, 4);
  EXPECT_EQ(d->last_percent, (std::vector<double>{0.1, 0.2}));
}

TEST(StopRule, ParametersOutsideTheirRangeAreNamed) {
  try {
    surface_stop({1, 2}, rule(0, 0.5, 1));
    FAIL() << "a window of 0 was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--stop-window 0"), std::string::npos) << e.what();
  }
  EXPECT_THROW(surface_stop({1, 2}, rule(2, -1.0, 1)), std::invalid_argument);
  EXPECT_THROW(new_surface(plane(0, 0), plane(0, 0), 0.0), std::invalid_argument);
}

TEST(NewSurface, DuplicateAddsNothingAndAPlaneOneCentimetreAwayAddsEverything) {
  const PointCloud model = plane(0, 0);
  const NewSurface same = new_surface(model, model, 0.005);
  EXPECT_EQ(same.frame_points, 2601);
  EXPECT_EQ(same.model_points, 2601);
  EXPECT_EQ(same.new_points, 0);
  EXPECT_DOUBLE_EQ(same.percent_of_model(), 0.0);
  // 4 mm above: every point within 5 mm of the model.
  EXPECT_EQ(new_surface(plane(0, 0.004f), model, 0.005).new_points, 0);
  const NewSurface above = new_surface(plane(0, 0.01f), model, 0.005);
  EXPECT_EQ(above.new_points, 2601);
  EXPECT_DOUBLE_EQ(above.percent_of_model(), 100.0);
  EXPECT_DOUBLE_EQ(above.percent_of_frame(), 100.0);
}

TEST(NewSurface, HalfOverlappingPlaneCountsTheColumnsBeyondTheRadius) {
  // The frame spans x in [0.05, 0.15], the model x in [0, 0.1]: columns x = 0.106 ... 0.150 lie
  // more than 5 mm beyond the model's edge (0.104 is 4 mm from it): 23 columns of 51 points.
  const NewSurface n = new_surface(plane(0.05f, 0), plane(0, 0), 0.005);
  EXPECT_EQ(n.new_points, 23 * 51);
  EXPECT_NEAR(n.percent_of_model(), 100.0 * 1173 / 2601, 1e-9);  // 45.10 %
  EXPECT_NEAR(n.percent_of_frame(), 100.0 * 23 / 51, 1e-9);
}

TEST(NewSurface, FirstViewIsAllNew) {
  const NewSurface n = new_surface(plane(0, 0), {}, 0.005);
  EXPECT_EQ(n.new_points, 2601);
  EXPECT_EQ(n.model_points, 0);
  EXPECT_DOUBLE_EQ(n.percent_of_model(), 100.0);
}

TEST(NewSurface, FiguresReadBackFromScanJsonViews) {
  NewSurface n;
  n.frame_points = 100;
  n.new_points = 3;
  n.model_points = 600;
  n.radius_m = 0.005;
  const nlohmann::json views = {
      {{"view", 0}, {"frame_file", "frames/view_001.ply"}, {"merged", true}, {"new_surface", to_json(n)}},
      {{"view", 1}, {"move", {{"status", "unreachable"}}}},                     // no frame: not counted
      {{"view", 2}, {"frame_file", "frames/view_003.ply"}, {"merged", false}}};  // rejected: NaN
  const std::vector<double> f = new_surface_figures(views);
  ASSERT_EQ(f.size(), 2u);
  EXPECT_DOUBLE_EQ(f[0], 0.5);
  EXPECT_TRUE(std::isnan(f[1]));
}
