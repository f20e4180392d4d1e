// The surface stop rule on hand-made per-view curves, and the figures it reads from recorded views
// (the new-surface count itself: core/perception/test/new_surface_test.cpp).
#include "core/scan/stop_rule.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/scan/scan_record.hpp"

using namespace pbnbv;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

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
}

TEST(NewSurface, FiguresOfTheRecordedViews) {
  std::vector<ViewRecord> views(3);
  views[0].registration = RegisteredCloud{};
  views[0].registration->accepted = true;
  views[0].registration->frame_file = "frames/view_001.ply";
  views[0].registration->new_surface = NewSurface{100, 3, 600, 0.005};
  views[1].view = 1;  // unreachable: no frame, not counted
  views[2].view = 2;  // rejected: NaN
  views[2].registration = RegisteredCloud{};
  views[2].registration->frame_file = "frames/view_003.ply";
  const std::vector<double> f = new_surface_figures(views);
  ASSERT_EQ(f.size(), 2u);
  EXPECT_DOUBLE_EQ(f[0], 0.5);
  EXPECT_TRUE(std::isnan(f[1]));
}
