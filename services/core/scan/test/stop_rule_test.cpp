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

namespace {

SecondsStopRule seconds_rule(int window, double percent_per_s, int min_views) {
  SecondsStopRule r;
  r.window = window;
  r.min_percent_per_s = percent_per_s;
  r.min_views = min_views;
  return r;
}

}  // namespace

TEST(SecondsStopRule, StopsWhenTheLastViewsAddTooLittlePerSecondOfRigTime) {
  // New surface (%) and rig seconds per view. Gain per second over two views: views 4-5 1.5/4 =
  // 0.375 %/s, views 5-6 0.5/5 = 0.1, views 6-7 0.3/5 = 0.06, views 7-8 0.4/8 = 0.05.
  const std::vector<ViewGain> views{{100, 3}, {40, 2}, {10, 2}, {1.0, 2}, {0.5, 2}, {0.0, 3}, {0.3, 2}, {0.1, 6}};
  auto d = first_seconds_stop(views, seconds_rule(2, 0.08, 3));
  ASSERT_TRUE(d);
  EXPECT_EQ(d->after_views, 7);
  EXPECT_EQ(d->last_percent, (std::vector<double>{0.0, 0.3}));
  EXPECT_EQ(d->reason, "views 6-7 added 0.30 % new surface in 5.0 s of rig time (0.060 %/s, under 0.080 %/s)");
  // Under 0.2 %/s: views 5-6 (0.1 %/s); under 0.05 %/s: never (views 7-8 are exactly 0.05).
  EXPECT_EQ(first_seconds_stop(views, seconds_rule(2, 0.2, 3))->after_views, 6);
  EXPECT_FALSE(first_seconds_stop(views, seconds_rule(2, 0.05, 3)));
  // The same new surface bought with more rig time stops sooner: view 5 taking 20 s, not 2 s,
  // puts views 4-5 at 1.5/22 = 0.068 %/s.
  std::vector<ViewGain> slow = views;
  slow[4].rig_s = 20;
  EXPECT_EQ(first_seconds_stop(slow, seconds_rule(2, 0.08, 3))->after_views, 5);
  // Never before min_views; a window of one view.
  EXPECT_EQ(first_seconds_stop(views, seconds_rule(1, 0.3, 3))->after_views, 5);  // 0.5 / 2 = 0.25 %/s
  EXPECT_EQ(first_seconds_stop(views, seconds_rule(1, 0.3, 6))->after_views, 6);
}

TEST(SecondsStopRule, AViewNotMergedAddsNothingAndAViewWithoutRigTimeIsNotJudged) {
  // View 3 rejected by the registration: it added nothing in its 4 s (3/6 = 0.5 %/s over views 2-3).
  EXPECT_EQ(first_seconds_stop({{100, 2}, {3, 2}, {kNaN, 4}}, seconds_rule(2, 0.6, 1))->after_views, 3);
  // View 3's rig time not known: views 2-3 are not judged; views 3-4 neither; views 4-5 are.
  const std::vector<ViewGain> unknown{{100, 2}, {0.1, 2}, {0.1, kNaN}, {0.1, 2}, {0.1, 2}};
  EXPECT_EQ(first_seconds_stop(unknown, seconds_rule(2, 0.5, 1))->after_views, 5);
  EXPECT_THROW(seconds_stop({{1, 1}}, seconds_rule(0, 0.5, 1)), std::invalid_argument);
  EXPECT_THROW(seconds_stop({{1, 1}}, seconds_rule(1, -0.5, 1)), std::invalid_argument);
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
  // The seconds rule's figures: the same views, with motion + settle + capture (not compute).
  views[0].rig_time = RigTime{2.5, 0.25, 0.5, 7.0};
  const std::vector<ViewGain> g = view_gains(views);
  ASSERT_EQ(g.size(), 2u);
  EXPECT_DOUBLE_EQ(g[0].new_percent, 0.5);
  EXPECT_DOUBLE_EQ(g[0].rig_s, 3.25);
  EXPECT_TRUE(std::isnan(g[1].new_percent));
  EXPECT_TRUE(std::isnan(g[1].rig_s));
}
