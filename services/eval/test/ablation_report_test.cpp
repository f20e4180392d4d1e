// write_ablation with several planners per value: one table row per (value, planner), the
// raycast / pbnbv time ratio per value, and the time plot against the value.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "eval/bench.hpp"
#include "core/io/json.hpp"
#include "file_test_util.hpp"

namespace fs = std::filesystem;

namespace pbnbv::eval {
namespace {

PlannerSummary summary(PlannerKind k, double median_ms, std::vector<double> coverage) {
  PlannerSummary p;
  p.planner = k;
  p.planner_ms_median = median_ms;
  p.planner_ms_mean = median_ms;
  p.coverage_by_view = std::move(coverage);
  p.complete = 2;
  return p;
}

BenchResult bench(const fs::path& out, double pbnbv_ms, double raycast_ms) {
  BenchResult r;
  r.spec.views = 2;
  r.spec.planners = {PlannerKind::kPbnbv, PlannerKind::kRaycast};
  r.spec.out = out;
  r.planners = {summary(PlannerKind::kPbnbv, pbnbv_ms, {30, 90}), summary(PlannerKind::kRaycast, raycast_ms, {30, 80})};
  return r;
}

using pbnbv::read_text;  // core/io: the whole file, or an error naming it

TEST(AblationReport, TimeRatio) {
  EXPECT_DOUBLE_EQ(*time_ratio_raycast_to_pbnbv(bench("x", 20, 600)), 30.0);
  BenchResult only = bench("x", 20, 600);
  only.planners.pop_back();
  EXPECT_FALSE(time_ratio_raycast_to_pbnbv(only).has_value());
  BenchResult failed = bench("x", 20, 600);
  failed.planners[1].complete = 0;  // no raycast scan completed: no ratio
  EXPECT_FALSE(time_ratio_raycast_to_pbnbv(failed).has_value());
}

TEST(AblationReport, SeveralPlannersPerValue) {
  const fs::path dir = fs::temp_directory_path() / ("pbnbv_ablation_test_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const std::vector<std::pair<std::string, BenchResult>> runs = {
      {"0.03", bench(dir / "resolution=0.03", 20, 60)}, {"0.01", bench(dir / "resolution=0.01", 25, 1000)}};
  write_ablation("resolution", runs, dir);

  const std::string md = read_text(dir / "ablation.md");
  EXPECT_NE(md.find("| resolution 0.03 pbnbv | 30.0 | 90.0 | never | 20.0 ms (20.0) |"), std::string::npos) << md;
  EXPECT_NE(md.find("| resolution 0.01 raycast | 30.0 | 80.0 | never | 1000 ms (1000) |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 0.03 | 20.0 ms | 60.0 ms | 3.0x |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 0.01 | 25.0 ms | 1000 ms | 40.0x |"), std::string::npos) << md;
  EXPECT_NE(md.find("ablation_time.png"), std::string::npos);

  const nlohmann::json j = nlohmann::json::parse(read_text(dir / "ablation.json"));
  ASSERT_EQ(j["values"].size(), 4u);
  EXPECT_EQ(j["values"][3]["planner"], "raycast");
  EXPECT_EQ(j["values"][3]["value"], "0.01");
  ASSERT_EQ(j["time_ratios"].size(), 2u);
  EXPECT_DOUBLE_EQ(j["time_ratios"][1]["raycast_to_pbnbv"].get<double>(), 40.0);
  EXPECT_TRUE(fs::exists(dir / "ablation.png"));
  EXPECT_GT(fs::file_size(dir / "ablation_time.png"), 1000u);

  // Values that are not numbers (initial views): no time plot.
  const fs::path views = dir / "views";
  write_ablation("initial-view", {{"0.9,0,0", bench(views / "a", 20, 60)}}, views);
  EXPECT_FALSE(fs::exists(views / "ablation_time.png"));
  EXPECT_EQ(read_text(views / "ablation.md").find("ablation_time.png"), std::string::npos);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace pbnbv::eval
