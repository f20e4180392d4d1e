// The benchmark's surface metrics: a planner's means over its complete runs (summary.json)
// and report.md's table, on hand-made figures.
#include <gtest/gtest.h>

#include <string>

#include "eval/bench.hpp"
#include "eval/evaluate.hpp"

namespace pbnbv::eval {
namespace {

SurfaceMetrics metrics(double mean_mm, double f) {
  SurfaceMetrics m;
  m.model = "cloud";
  m.threshold_m = 0.005;
  m.accuracy.count = 100;
  m.accuracy.mean_m = mean_mm * 1e-3;
  m.accuracy.median_m = mean_mm * 1e-3 / 2;
  m.accuracy.rmse_m = mean_mm * 1e-3 * 2;
  m.accuracy.p95_m = mean_mm * 1e-3 * 3;
  m.completeness.mean_m = 1e-3;
  m.precision = f;
  m.recall = f;
  m.f_score = f;
  return m;
}

ObjectRun run(const std::string& name, bool complete, std::optional<SurfaceMetrics> cloud) {
  ObjectRun r;
  r.object = name;
  r.complete = complete;
  r.coverage_by_view = {50, 90};
  r.cloud_metrics = cloud;
  return r;
}

TEST(SurfaceSummary, MeansOverTheCompleteObjectsThatHaveThem) {
  // a and b count; c failed (its figures are left out), d has no cloud metrics.
  const PlannerSummary s = summarise(PlannerKind::kPbnbv,
                                     {run("a", true, metrics(1.0, 0.9)), run("b", true, metrics(3.0, 0.7)),
                                      run("c", false, metrics(100.0, 0.0)), run("d", true, std::nullopt)},
                                     2);
  EXPECT_EQ(s.cloud_metrics.objects, 2);
  EXPECT_DOUBLE_EQ(s.cloud_metrics.accuracy_mean_mm, 2.0);
  EXPECT_DOUBLE_EQ(s.cloud_metrics.accuracy_median_mm, 1.0);
  EXPECT_DOUBLE_EQ(s.cloud_metrics.accuracy_rmse_mm, 4.0);
  EXPECT_DOUBLE_EQ(s.cloud_metrics.accuracy_p95_mm, 6.0);
  EXPECT_DOUBLE_EQ(s.cloud_metrics.completeness_mean_mm, 1.0);
  EXPECT_DOUBLE_EQ(s.cloud_metrics.f_score, 0.8);
  EXPECT_EQ(s.mesh_metrics.objects, 0);

  BenchResult r;
  r.planners = {s};
  const nlohmann::json j = to_json(r);
  EXPECT_DOUBLE_EQ(j["pbnbv"]["surface_metrics"]["cloud"]["f_score"].get<double>(), 0.8);
  EXPECT_FALSE(j["pbnbv"]["surface_metrics"].contains("mesh"));
  EXPECT_DOUBLE_EQ(j["pbnbv"]["runs"]["a"]["surface_metrics"]["cloud"]["accuracy"]["mean_mm"].get<double>(), 1.0);

  const std::string md = surface_metrics_markdown(r.planners, MetricParams{});
  EXPECT_NE(md.find("| pbnbv | cloud | 2 | 2.00 | 1.00 | 4.00 | 6.00 | 1.00 | 0.800 | 0.800 | 0.800 |"), std::string::npos)
      << md;
  EXPECT_NE(md.find("precision @5.0 mm"), std::string::npos) << md;

  // No planner with metrics: no section.
  r.planners = {summarise(PlannerKind::kPbnbv, {run("d", true, std::nullopt)}, 2)};
  EXPECT_EQ(surface_metrics_markdown(r.planners, MetricParams{}), "");
}

}  // namespace
}  // namespace pbnbv::eval
