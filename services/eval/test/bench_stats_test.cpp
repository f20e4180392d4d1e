// The benchmark's statistics over many objects from many first views, on figures checkable by
// hand: the bootstrap interval of a mean, the means and spread over runs (objects x first
// views), the per-object means, the gap to the oracle paired by object and first view, the
// halves of the tuning set, and how summary.json and report.md carry them.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/base/version.hpp"
#include "eval/bench.hpp"
#include "core/io/json.hpp"
#include "file_test_util.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace pbnbv::eval {
namespace {

ObjectRun run(const std::string& object, int first_view, std::vector<double> coverage) {
  ObjectRun r;
  r.object = object;
  r.first_view = first_view;
  r.complete = !coverage.empty();
  if (!r.complete) r.error = "the scan did not complete";
  r.coverage_by_view = std::move(coverage);
  r.views_to_95 = views_to_reach(r.coverage_by_view, 95.0);
  r.planner_ms = {10.0, 20.0};
  return r;
}

TEST(Bootstrap, EqualObjectsGiveAnIntervalOfZeroWidthAtTheirValue) {
  const std::vector<Interval> ci = bootstrap_mean_ci95({{50, 90}, {50, 90}, {50, 90}});
  ASSERT_EQ(ci.size(), 2u);
  EXPECT_EQ(ci[0].lo, 50.0);
  EXPECT_EQ(ci[0].hi, 50.0);
  EXPECT_EQ(ci[1].lo, 90.0);
  EXPECT_EQ(ci[1].hi, 90.0);
  // One object: its value.
  const std::vector<Interval> one = bootstrap_mean_ci95({{4.5}});
  EXPECT_EQ(one[0].lo, 4.5);
  EXPECT_EQ(one[0].hi, 4.5);
}

// Two objects: a resample is both of the first (probability 1/4), one of each (1/2) or both of
// the second (1/4); of 2,000 resamples about 500 are all of the first, so the 2.5th percentile
// (the 50th resample mean) is the first object's value and the 97.5th the second's.
TEST(Bootstrap, TwoObjectsIntervalEndsAreTheirValues) {
  const std::vector<Interval> ci = bootstrap_mean_ci95({{40, 2}, {60, 5}});
  ASSERT_EQ(ci.size(), 2u);
  EXPECT_EQ(ci[0].lo, 40.0);
  EXPECT_EQ(ci[0].hi, 60.0);
  EXPECT_EQ(ci[1].lo, 2.0);
  EXPECT_EQ(ci[1].hi, 5.0);
  // Deterministic: the same seed, the same interval; no rows, none; rows must match.
  const std::vector<std::vector<double>> rows = {{10}, {20}, {35}, {41}, {70}};
  const std::vector<Interval> a = bootstrap_mean_ci95(rows), b = bootstrap_mean_ci95(rows);
  EXPECT_EQ(a[0].lo, b[0].lo);
  EXPECT_EQ(a[0].hi, b[0].hi);
  EXPECT_LT(a[0].lo, 35.2);  // around the mean 35.2, inside the values' range
  EXPECT_GT(a[0].hi, 35.2);
  EXPECT_GT(a[0].lo, 10.0);
  EXPECT_LT(a[0].hi, 70.0);
  EXPECT_TRUE(bootstrap_mean_ci95({}).empty());
  EXPECT_THROW(bootstrap_mean_ci95({{1, 2}, {3}}), std::invalid_argument);
  EXPECT_THROW(bootstrap_mean_ci95({{1}}, 0), std::invalid_argument);
}

// Object a from two first views, b from two of which one failed.
std::vector<ObjectRun> two_objects_two_first_views() {
  return {run("a", 1, {40, 90, 96}), run("b", 1, {20, 70, 80}), run("a", 2, {60, 96, 98}), run("b", 2, {})};
}

TEST(BenchStatistics, MeansAndSpreadOverRunsAndPerObjectMeans) {
  const PlannerSummary s = summarise(PlannerKind::kPbnbv, two_objects_two_first_views(), 3);
  EXPECT_EQ(s.complete, 3);  // runs
  EXPECT_EQ(s.failed, 1);
  // Over the three complete runs.
  ASSERT_EQ(s.coverage_by_view.size(), 3u);
  EXPECT_DOUBLE_EQ(s.coverage_by_view[0], 40.0);           // (40 + 20 + 60) / 3
  EXPECT_DOUBLE_EQ(s.coverage_by_view[1], 256.0 / 3.0);    // (90 + 70 + 96) / 3
  EXPECT_DOUBLE_EQ(s.coverage_by_view[2], 274.0 / 3.0);    // (96 + 80 + 98) / 3
  EXPECT_EQ(s.coverage_min_by_view, (std::vector<double>{20, 70, 80}));
  EXPECT_EQ(s.coverage_max_by_view, (std::vector<double>{60, 96, 98}));
  EXPECT_EQ(s.reached_95, 2);                             // a from both first views
  EXPECT_DOUBLE_EQ(*s.views_to_95, 2.5);                  // views 3 and 2
  // Per object, mean over its complete first views.
  ASSERT_EQ(s.per_object.size(), 2u);
  const ObjectMean& a = s.per_object[0];
  EXPECT_EQ(a.object, "a");
  EXPECT_EQ(a.runs_complete, 2);
  EXPECT_EQ(a.runs_failed, 0);
  EXPECT_EQ(a.coverage_by_view, (std::vector<double>{50, 93, 97}));
  EXPECT_DOUBLE_EQ(*a.views_to_95, 2.5);
  EXPECT_EQ(a.runs_reaching_95, 2);
  const ObjectMean& b = s.per_object[1];
  EXPECT_EQ(b.runs_complete, 1);
  EXPECT_EQ(b.runs_failed, 1);
  EXPECT_EQ(b.coverage_by_view, (std::vector<double>{20, 70, 80}));
  EXPECT_FALSE(b.views_to_95.has_value());
  // The intervals over the two objects: their values are the ends (two objects, see above).
  EXPECT_EQ(s.objects_complete, 2);
  ASSERT_EQ(s.coverage_ci95_by_view.size(), 3u);
  EXPECT_EQ(s.coverage_ci95_by_view[0].lo, 20.0);
  EXPECT_EQ(s.coverage_ci95_by_view[0].hi, 50.0);
  EXPECT_EQ(s.coverage_ci95_by_view[2].lo, 80.0);
  EXPECT_EQ(s.coverage_ci95_by_view[2].hi, 97.0);
  // Views to 95 %: b never reaches it and is left out; a alone.
  EXPECT_EQ(s.objects_reaching_95, 1);
  ASSERT_TRUE(s.views_to_95_ci95.has_value());
  EXPECT_EQ(s.views_to_95_ci95->lo, 2.5);
  EXPECT_EQ(s.views_to_95_ci95->hi, 2.5);
  // The stop rule's worst run is named by its folder.
  EXPECT_EQ(s.stop_rule.objects, 3);
}

TEST(BenchStatistics, GapToTheOraclePairsRunsByObjectAndFirstView) {
  std::vector<PlannerSummary> p = {
      summarise(PlannerKind::kPbnbv, {run("a", 1, {40, 90, 96}), run("a", 2, {60, 96, 98})}, 3),
      summarise(PlannerKind::kOracle, {run("a", 2, {70, 99, 99}), run("a", 1, {50, 95, 99})}, 3)};
  add_gaps_to_oracle(p, 3);
  EXPECT_EQ(p[0].gap_objects, 2);
  // First view 1: 10, 5, 3; first view 2: 10, 3, 1.
  EXPECT_EQ(p[0].gap_to_oracle_by_view, (std::vector<double>{10, 4, 2}));
}

TEST(BenchStatistics, RunFoldersAndFirstViews) {
  EXPECT_EQ(run_folder("bunny", 1), "bunny");
  EXPECT_EQ(run_folder("bunny", 3), "bunny-fv3");
  BenchSpec s;
  EXPECT_TRUE(first_view_directions(s).empty());  // one first view: the default
  s.first_views = 4;
  const std::vector<Eigen::Vector3d> full = first_view_directions(s);
  ASSERT_EQ(full.size(), 3u);
  s.area = CandidateArea::kHemisphere;
  for (const auto& d : first_view_directions(s)) {
    EXPECT_NEAR(d.norm(), 1.0, 1e-12);
    EXPECT_GE(d.z(), 0.0);
  }
  // More first views keep the first ones (a folder's benchmark may gain first views).
  s.area = CandidateArea::kFullSphere;
  s.first_views = 6;
  const std::vector<Eigen::Vector3d> more = first_view_directions(s);
  EXPECT_EQ(std::vector<Eigen::Vector3d>(more.begin(), more.begin() + 3), full);
  // The distance of the default first view: the scan's working distance (0.6 m) plus half the
  // normalised box's diagonal; the built-in box 1.2 x 1.0 x 0.8 scaled to a 0.3 m shortest edge
  // is 0.45 x 0.375 x 0.3 m.
  const double half_diagonal = 0.5 * std::sqrt(0.45 * 0.45 + 0.375 * 0.375 + 0.3 * 0.3);
  EXPECT_NEAR(default_first_view_distance("box", 0.3, 0.6, std::nullopt), 0.6 + half_diagonal, 1e-9);
  // A closer camera (a short-range one: --working-distance 0.25) starts 0.35 m nearer.
  EXPECT_NEAR(default_first_view_distance("box", 0.3, 0.25, std::nullopt), 0.25 + half_diagonal, 1e-9);
}

TEST(BenchStatistics, FirstViewsAreRangeCheckedAndExcludeAFixedInitialView) {
  BenchSpec s;
  s.objects = {"sphere"};
  s.out = "/tmp/x";
  s.first_views = 11;
  try {
    s.validate();
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--first-views 11 is outside its range [1, 10]"), std::string::npos) << e.what();
  }
  s.first_views = 2;
  s.initial_view = Eigen::Vector3d(0.9, 0, 0);
  try {
    s.validate();
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--first-views 2 draws the first views 2..2 while --initial-view fixes"),
              std::string::npos)
        << e.what();
  }
  s.first_views = 1;
  EXPECT_NO_THROW(s.validate());
}

using pbnbv::read_text;  // core/io: the whole file, or an error naming it

// Runs of two tuning objects (bunny: tune half, bear: confirm half) and a sphere (neither) from
// two first views; pbnbv and raycast.
BenchResult halves_result(const fs::path& out) {
  BenchResult r;
  r.spec.objects = {"bunny", "bear", "sphere"};
  r.spec.planners = {PlannerKind::kPbnbv, PlannerKind::kRaycast};
  r.spec.views = 3;
  r.spec.first_views = 2;
  r.spec.out = out;
  r.machine = {{"cpu", "test"}, {"cores", 2}};
  const std::vector<ObjectRun> pb = {run("bunny", 1, {40, 90, 96}), run("bunny", 2, {60, 96, 98}),
                                     run("bear", 1, {30, 80, 90}),  run("bear", 2, {30, 80, 92}),
                                     run("sphere", 1, {45, 95, 99}), run("sphere", 2, {45, 95, 99})};
  const std::vector<ObjectRun> rc = {run("bunny", 1, {40, 92, 97}), run("bunny", 2, {60, 94, 97}),
                                     run("bear", 1, {30, 85, 95}),  run("bear", 2, {30, 85, 95}),
                                     run("sphere", 1, {45, 96, 99}), run("sphere", 2, {})};
  r.planners = {summarise(PlannerKind::kPbnbv, pb, 3), summarise(PlannerKind::kRaycast, rc, 3)};
  r.halves = summarise_halves(r.spec, r.planners);
  return r;
}

TEST(BenchStatistics, HalvesSummaryJsonAndReport) {
  const fs::path dir = fs::temp_directory_path() / ("pbnbv_bench_stats_test_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const BenchResult r = halves_result(dir);

  // The halves: bunny alone in tune, bear alone in confirm; the sphere in neither.
  ASSERT_EQ(r.halves.size(), 2u);
  EXPECT_EQ(r.halves[0].half, ObjectSet::kTune);
  EXPECT_EQ(r.halves[0].objects, (std::vector<std::string>{"bunny"}));
  EXPECT_EQ(r.halves[1].objects, (std::vector<std::string>{"bear"}));
  const PlannerSummary& tune_pb = r.halves[0].planners[0];
  EXPECT_EQ(tune_pb.complete, 2);
  EXPECT_EQ(tune_pb.coverage_by_view, (std::vector<double>{50, 93, 97}));
  EXPECT_EQ(r.halves[1].planners[0].coverage_by_view, (std::vector<double>{30, 80, 91}));
  // Members of one half only: no halves.
  BenchSpec one_half = r.spec;
  one_half.objects = {"bunny", "sphere"};
  EXPECT_TRUE(summarise_halves(one_half, r.planners).empty());
  EXPECT_EQ(objects_text(r), "5-6 of 6 runs (3 objects x 2 first views; failed: raycast 1)");

  const json j = to_json(r);
  EXPECT_EQ(j["pbnbv_version"], std::string(pbnbv_version()));  // summary.json names its writer
  EXPECT_EQ(j["first_views"], 2);
  EXPECT_EQ(j["first_view_directions"].size(), 1u);
  EXPECT_EQ(j["pbnbv"]["runs_complete"], 6);
  EXPECT_EQ(j["pbnbv"]["runs_reaching_95"], 4);  // bunny twice, sphere twice
  EXPECT_EQ(j["pbnbv"]["objects_complete"], 3);
  EXPECT_EQ(j["pbnbv"]["coverage_ci95_by_view"].size(), 3u);
  EXPECT_EQ(j["pbnbv"]["coverage_ci95_by_view"][0].size(), 2u);
  EXPECT_EQ(j["pbnbv"]["objects"]["bunny"]["coverage_by_view"], json({50, 93, 97}));
  EXPECT_EQ(j["pbnbv"]["runs"]["bunny-fv2"]["first_view"], 2);
  EXPECT_EQ(j["pbnbv"]["runs"]["bunny-fv2"]["object"], "bunny");
  EXPECT_EQ(j["pbnbv"]["runs"]["bunny"]["coverage_by_view"], json({40, 90, 96}));
  EXPECT_EQ(j["halves"]["tune"]["objects"], json({"bunny"}));
  EXPECT_EQ(j["halves"]["confirm"]["pbnbv"]["coverage_by_view"], json({30, 80, 91}));
  EXPECT_TRUE(j["halves"]["tune"]["raycast"].contains("coverage_ci95_by_view"));
  EXPECT_FALSE(j["halves"]["tune"]["pbnbv"].contains("runs"));  // the runs are listed once, above
  ASSERT_EQ(j["failed_scans"].size(), 1u);
  EXPECT_EQ(j["failed_scans"][0]["run"], "sphere-fv2");
  EXPECT_EQ(j["failed_scans"][0]["first_view"], 2);

  write_report(r);
  const std::string md = read_text(dir / "report.md");
  EXPECT_NE(md.find("mean over runs: objects x first views"), std::string::npos) << md;
  // The line of intervals under the main table.
  EXPECT_NE(md.find("- pbnbv (3 objects): coverage after view 2 ["), std::string::npos) << md;
  // Per object and planner: coverage after views 2 and 3 (the budget), views to 95 %.
  EXPECT_NE(md.find("| bunny | pbnbv | 93.0 | 97.0 | 2.50 (2 of 2) |"), std::string::npos) << md;
  EXPECT_NE(md.find("| bear | pbnbv | 80.0 | 91.0 | never (0 of 2) |"), std::string::npos) << md;
  EXPECT_NE(md.find("| sphere | raycast | 96.0 | 99.0 | 2.00 (1 of 1) |"), std::string::npos) << md;
  // pbnbv ends 4 points below raycast on the bear, 0 on the bunny and the sphere.
  EXPECT_NE(md.find("more than 1 point below raycast: bear (91.00 against 95.00)."), std::string::npos) << md;
  // A table per half, with the intervals after views 2 and 3 (4 and 10 are past the budget).
  EXPECT_NE(md.find("### tune half (1 object: bunny)"), std::string::npos) << md;
  EXPECT_NE(md.find("### confirm half (1 object: bear)"), std::string::npos) << md;
  EXPECT_NE(md.find("| 95 % interval after 2 | 95 % interval after 3 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| pbnbv | 50.0 | 93.0 | 97.0 | 2.50 (2 of 2 reach it) | 15.0 ms (15.0) | 2 | [93.0, 93.0] | [97.0, 97.0] |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("run | planner | stop view"), std::string::npos);
  EXPECT_NE(md.find("| bunny-fv2 | pbnbv |"), std::string::npos);
  // Not the default set: no foreign reference curve.
  EXPECT_EQ(md.find("authors' release"), std::string::npos);
  EXPECT_EQ(read_text(dir / "coverage.svg").find("authors' release"), std::string::npos);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace pbnbv::eval
