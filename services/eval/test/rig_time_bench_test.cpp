// Rig time in the benchmark, on hand-made scans whose rig times are known: the rig time at the end
// of each captured view, the time to 90 % and 95 % of the observable surface, the means over the
// runs, the coverage against rig time at common times, and how summary.json and report.md carry
// them. Every figure below is worked out by hand in its comment.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/scan/scan_record.hpp"
#include "eval/bench.hpp"
#include "core/io/json.hpp"
#include "file_test_util.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace pbnbv::eval {
namespace {

using pbnbv::read_text;  // core/io: the whole file, or an error naming it

// A recorded view with rig time (motion, settle, capture, compute), with a frame or not.
ViewRecord view(int i, RigTime t, bool frame) {
  ViewRecord v;
  v.view = i;
  v.rig_time = t;
  if (frame) {
    RegisteredCloud r;
    r.accepted = true;
    r.frame_file = "frames/view_00" + std::to_string(i + 1) + ".ply";
    v.registration = r;
  }
  return v;
}

// Four views; the second's move was refused (no frame, 1 s of waiting). Per view: 13.0, 1.0,
// 11.0 and 8.0 s, so the three views with a frame end at 13, 13 + 1 + 11 = 25 and 25 + 8 = 33 s.
std::vector<ViewRecord> four_views() {
  return {view(0, {10.0, 0.5, 0.25, 2.25}, true), view(1, {0.0, 0.0, 0.0, 1.0}, false),
          view(2, {8.0, 0.5, 0.25, 2.25}, true), view(3, {6.0, 0.5, 0.25, 1.25}, true)};
}

TEST(RigTimeBench, RigTimeAtTheEndOfEachViewWithAFrame) {
  std::vector<ViewRecord> views = four_views();
  EXPECT_EQ(rig_time_at_frames(views), (std::vector<double>{13.0, 25.0, 33.0}));
  const RigTimeSum sum = sum_rig_time(views);
  EXPECT_EQ(sum.sum.motion_s, 24.0);
  EXPECT_EQ(sum.sum.settle_s, 1.5);
  EXPECT_EQ(sum.sum.capture_s, 0.75);
  EXPECT_EQ(sum.sum.compute_s, 6.75);
  EXPECT_EQ(sum.sum.total_s(), 33.0);
  EXPECT_EQ(sum.views, 4);
  EXPECT_EQ(sum.views_incomplete, 0);
  // A view whose compute is not known (the scan resumed after it): not known from there on.
  views[2].rig_time->compute_s = RigTime::kUnset;
  const std::vector<double> t = rig_time_at_frames(views);
  ASSERT_EQ(t.size(), 3u);
  EXPECT_EQ(t[0], 13.0);
  EXPECT_TRUE(std::isnan(t[1]));
  EXPECT_TRUE(std::isnan(t[2]));
  EXPECT_EQ(sum_rig_time(views).views_incomplete, 1);
  // A record written before rig time: none.
  for (ViewRecord& v : views) v.rig_time.reset();
  EXPECT_TRUE(rig_time_at_frames(views).empty());
}

TEST(RigTimeBench, TimeToReachIsTheRigTimeAtTheFirstViewThatReachesIt) {
  const std::vector<double> observable = {60, 92, 96}, t = {13, 25, 33};
  EXPECT_EQ(rig_time_to_reach(observable, t, 90.0), 25.0);
  EXPECT_EQ(rig_time_to_reach(observable, t, 95.0), 33.0);
  EXPECT_EQ(rig_time_to_reach(observable, t, 60.0), 13.0);
  EXPECT_FALSE(rig_time_to_reach(observable, t, 97.0));                   // never reached
  EXPECT_FALSE(rig_time_to_reach(observable, {13, NAN, 33}, 90.0));       // that view not measured
  EXPECT_FALSE(rig_time_to_reach(observable, {13}, 90.0));                // nor recorded
}

TEST(RigTimeBench, TheGridIsOneTwoOrFiveTimesAPowerOfTenAndCoversTheLongestRun) {
  EXPECT_EQ(rig_time_grid(33, 10), (std::vector<double>{0, 5, 10, 15, 20, 25, 30, 35}));  // 2 s would take 17 steps
  EXPECT_EQ(rig_time_grid(20, 10), (std::vector<double>{0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20}));
  EXPECT_EQ(rig_time_grid(0), (std::vector<double>{0}));
  EXPECT_EQ(rig_time_grid(33).size(), 166u);  // 0.2 s steps: 0 .. 33.0
}

// Two runs measured at every view and one recorded before rig time.
// Run 1 (four_views): views end at 13, 25, 33 s with 60, 92, 96 % observable.
// Run 2: 10, 20, 30 s with 70, 91, 93 %; its parts 24 + 1.5 + 0.5 + 4 = 30 s.
std::vector<ObjectRun> runs() {
  ObjectRun a;
  a.object = "bunny";
  a.complete = true;
  a.coverage_by_view = a.observable_by_view = {60, 92, 96};
  a.rig_time_by_view = rig_time_at_frames(four_views());
  a.rig_time = sum_rig_time(four_views()).sum;
  ObjectRun b;
  b.object = "teapot";
  b.complete = true;
  b.coverage_by_view = b.observable_by_view = {70, 91, 93};
  b.rig_time_by_view = {10, 20, 30};
  b.rig_time = RigTime{24.0, 1.5, 0.5, 4.0};
  ObjectRun old;
  old.object = "cow";
  old.complete = true;
  old.coverage_by_view = old.observable_by_view = {80, 99, 99};
  return {a, b, old};
}

TEST(RigTimeBench, PlannerMeansOverTheRunsThatMeasuredIt) {
  const PlannerSummary p = summarise(PlannerKind::kPbnbv, runs(), 3);
  EXPECT_EQ(p.complete, 3);
  EXPECT_EQ(p.rig_time_runs, 2);  // not the cow's
  // Per scan: motion (24 + 24) / 2, settle 1.5, capture (0.75 + 0.5) / 2, compute (6.75 + 4) / 2.
  EXPECT_EQ(p.rig_time_mean.motion_s, 24.0);
  EXPECT_EQ(p.rig_time_mean.settle_s, 1.5);
  EXPECT_EQ(p.rig_time_mean.capture_s, 0.625);
  EXPECT_EQ(p.rig_time_mean.compute_s, 5.375);
  EXPECT_EQ(p.rig_time_mean.total_s(), 31.5);
  EXPECT_EQ(p.rig_time_by_view, (std::vector<double>{11.5, 22.5, 31.5}));
  // To 90 %: 25 s (run 1's view 2) and 20 s (run 2's view 2): 22.5 s over 2 runs. To 95 %: only
  // run 1, at 33 s.
  ASSERT_TRUE(p.rig_time_to_90);
  EXPECT_EQ(*p.rig_time_to_90, 22.5);
  EXPECT_EQ(p.rig_time_reaching_90, 2);
  ASSERT_TRUE(p.rig_time_to_95);
  EXPECT_EQ(*p.rig_time_to_95, 33.0);
  EXPECT_EQ(p.rig_time_reaching_95, 1);

  // Coverage at 0, 5, ..., 35 s: run 1 has 0 until 13 s, then 60, 92 from 25 s, 96 from 33 s;
  // run 2 has 0 until 10 s, then 70, 91 from 20 s, 93 from 30 s.
  const std::vector<double> times = rig_time_grid(33, 10);
  const CoverageOverTime c = coverage_at_rig_times(p.runs, times);
  EXPECT_EQ(c.runs, 2);
  EXPECT_EQ(c.mean, (std::vector<double>{0, 0, 35, 65, 75.5, 91.5, 92.5, 94.5}));
  EXPECT_EQ(c.lo, (std::vector<double>{0, 0, 0, 60, 60, 91, 92, 93}));
  EXPECT_EQ(c.hi, (std::vector<double>{0, 0, 70, 70, 91, 92, 93, 96}));
  EXPECT_EQ(coverage_at_rig_times({runs()[2]}, times).runs, 0);
}

TEST(RigTimeBench, SummaryJsonAndReportCarryIt) {
  const fs::path dir = fs::temp_directory_path() / ("pbnbv_rig_time_bench_test_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  BenchResult r;
  r.spec.objects = {"bunny", "teapot", "cow"};
  r.spec.planners = {PlannerKind::kPbnbv};
  r.spec.rig = RigKind::kArm;
  r.spec.area = CandidateArea::kHemisphere;
  r.spec.views = 3;
  r.spec.out = dir;
  r.planners = {summarise(PlannerKind::kPbnbv, runs(), 3)};
  r.machine = {{"cpu", "test"}, {"cores", 2}};

  const json j = to_json(r);
  const json& p = j["pbnbv"];
  EXPECT_EQ(p["rig_time_runs"], 2);
  EXPECT_EQ(p["rig_time_s"], json({{"motion", 24.0}, {"settle", 1.5}, {"capture", 0.625}, {"compute", 5.375}, {"total", 31.5}}));
  EXPECT_EQ(p["rig_time_s_by_view"], json({11.5, 22.5, 31.5}));
  EXPECT_EQ(p["rig_time_s_to_90"], 22.5);
  EXPECT_EQ(p["rig_time_s_to_90_runs"], 2);
  EXPECT_EQ(p["rig_time_s_to_95"], 33.0);
  EXPECT_EQ(p["rig_time_s_to_95_runs"], 1);
  EXPECT_EQ(p["runs"]["bunny"]["rig_time_s_by_view"], json({13.0, 25.0, 33.0}));
  EXPECT_EQ(p["runs"]["bunny"]["rig_time_s"]["total"], 33.0);
  EXPECT_EQ(p["runs"]["bunny"]["rig_time_s_to_90"], 25.0);
  EXPECT_EQ(p["runs"]["teapot"]["rig_time_s_to_95"], nullptr);  // never reaches 95 %
  EXPECT_FALSE(p["runs"]["cow"].contains("rig_time_s"));
  EXPECT_TRUE(j.contains("rig_time_rule"));

  write_report(r);
  const std::string md = read_text(dir / "report.md");
  // 31.5 s per scan, motion 24.0 of it (76 %).
  EXPECT_NE(md.find("| pbnbv | 2 | 31.5 | 24.0 | 1.50 | 0.62 | 5.4 | 76 % | 22.5 s (2 of 2) | 33.0 s (1 of 2) |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| pbnbv | 11.5 | 22.5 | 31.5 |"), std::string::npos) << md;
  EXPECT_NE(md.find("![observable coverage against rig time](observable_time.png)"), std::string::npos) << md;
  // The plot's data: 0.2 s steps to 33 s (the longest run), the mean at 25 s as above.
  const std::string csv = read_text(dir / "observable_time.csv");
  EXPECT_NE(csv.find("\n25,91.5,91,92,\"pbnbv\""), std::string::npos) << csv.substr(0, 400);
  EXPECT_NE(csv.find("\n33,94.5,93,96,\"pbnbv\""), std::string::npos) << csv.substr(0, 400);
  for (const char* f : {"observable_time.png", "observable_time.svg"}) EXPECT_TRUE(fs::exists(dir / f)) << f;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace pbnbv::eval
