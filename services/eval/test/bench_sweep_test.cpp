// Sweeps: every combination of the listed values once, the last setting varying fastest, each in
// a folder named for it; a value listed twice, or a combination that is not a valid bench,
// refused by name; the table across the combinations from their results.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "core/io/json.hpp"
#include "eval/bench_sweep.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace pbnbv::eval {
namespace {

BenchSpec base() {
  BenchSpec s;
  s.objects = {"sphere"};
  s.planners = {PlannerKind::kPbnbv, PlannerKind::kRandom};
  s.views = 3;
  s.out = "/tmp/pbnbv-sweep";
  return s;
}

std::string refusal(const BenchSpec& b, const SweepValues& v) {
  try {
    expand_sweep(b, v);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(BenchSweep, EveryCombinationOnceInAFolderNamedForIt) {
  SweepValues v;
  v.cameras = {CameraKind::kIdeal, CameraKind::kD435};
  v.resolutions = {0.03, 0.01};
  v.first_views = {1, 3};
  const Sweep s = expand_sweep(base(), v);
  EXPECT_EQ(s.out, fs::path("/tmp/pbnbv-sweep"));
  EXPECT_EQ(s.parameters, (std::vector<std::string>{"camera", "resolution", "first-views"}));
  ASSERT_EQ(s.benches.size(), 8u);  // 2 x 2 x 2
  EXPECT_EQ(s.benches[0].first, "camera=ideal,resolution=0.03,first-views=1");
  EXPECT_EQ(s.benches[1].first, "camera=ideal,resolution=0.03,first-views=3");
  EXPECT_EQ(s.benches[2].first, "camera=ideal,resolution=0.01,first-views=1");
  EXPECT_EQ(s.benches[7].first, "camera=d435,resolution=0.01,first-views=3");
  const BenchSpec& last = s.benches[7].second;
  EXPECT_EQ(last.camera, CameraKind::kD435);
  EXPECT_EQ(last.resolution_m, 0.01);
  EXPECT_EQ(last.first_views, 3);
  EXPECT_EQ(last.out, fs::path("/tmp/pbnbv-sweep/camera=d435,resolution=0.01,first-views=3"));
  EXPECT_EQ(last.views, 3);  // the rest as the base has it
  EXPECT_EQ(last.planners, base().planners);
  EXPECT_EQ(s.values[7], (std::vector<std::string>{"d435", "0.01", "3"}));
  EXPECT_EQ(s.lists.at("resolution"), "0.03,0.01");
  EXPECT_EQ(s.lists.at("camera"), "ideal,d435");
  EXPECT_EQ(s.lists.count("rig"), 0u);

  // Rig files: named by their files' names, given by their paths.
  SweepValues r;
  r.rigs = {RigKind::kArm};
  r.rig_models = {"/opt/rigs/rig_arm.xml", "/opt/rigs/rig_ur5e.xml"};
  const Sweep rigs = expand_sweep(base(), r);
  ASSERT_EQ(rigs.benches.size(), 2u);
  EXPECT_EQ(rigs.benches[1].first, "rig-model=rig_ur5e");
  EXPECT_EQ(rigs.benches[1].second.rig_model, "/opt/rigs/rig_ur5e.xml");
  EXPECT_EQ(rigs.benches[1].second.rig, RigKind::kArm);
  EXPECT_EQ(rigs.lists.at("rig-model"), "/opt/rigs/rig_arm.xml,/opt/rigs/rig_ur5e.xml");

  // Nothing swept: the bench itself, in its folder.
  const Sweep one = expand_sweep(base(), SweepValues{});
  ASSERT_EQ(one.benches.size(), 1u);
  EXPECT_EQ(one.benches[0].first, "");
  EXPECT_EQ(one.benches[0].second.out, fs::path("/tmp/pbnbv-sweep"));
  EXPECT_TRUE(one.parameters.empty());
}

TEST(BenchSweep, AValueListedTwiceOrACombinationThatIsNoBenchIsRefusedByName) {
  SweepValues v;
  v.resolutions = {0.03, 0.03};
  EXPECT_EQ(refusal(base(), v), "--resolution: '0.03' is listed twice");
  v = {};
  v.rig_models = {"/a/rig_arm.xml", "/b/rig_arm.xml"};
  EXPECT_EQ(refusal(base(), v), "--rig-model: 'rig_arm' is listed twice");
  v = {};
  v.cameras = {};
  EXPECT_EQ(refusal(base(), v), "--camera: no value");
  // A fixed first view rules out drawn ones: the combination that draws them is named.
  BenchSpec b = base();
  b.initial_view = Eigen::Vector3d(0, 0, 0.5);
  v = {};
  v.first_views = {1, 2};
  EXPECT_NE(refusal(b, v).find("the sweep's first-views=2: --first-views 2 draws"), std::string::npos) << refusal(b, v);
}

PlannerSummary planner(PlannerKind k, std::vector<double> coverage, double ms, double rig_time_s) {
  PlannerSummary p;
  p.planner = k;
  p.coverage_by_view = std::move(coverage);
  p.coverage_ci95_by_view = {{0, 0}, {0, 0}, {80.0, 90.5}};
  p.planner_ms_median = ms;
  p.complete = 2;
  p.failed = k == PlannerKind::kRandom ? 1 : 0;
  if (rig_time_s > 0) {
    p.rig_time_runs = 2;
    p.rig_time_mean = RigTime{rig_time_s - 3, 1, 1, 1};
    p.rig_time_to_95 = rig_time_s - 2;
  }
  return p;
}

TEST(BenchSweep, TheTableAcrossTheCombinations) {
  const fs::path dir = fs::temp_directory_path() / ("pbnbv_sweep_test_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  BenchSpec b = base();
  b.out = dir;
  SweepValues v;
  v.resolutions = {0.03, 0.01};
  const Sweep s = expand_sweep(b, v);
  std::vector<BenchResult> results(2);
  for (int i = 0; i < 2; ++i) {
    results[i].spec = s.benches[i].second;
    results[i].planners = {planner(PlannerKind::kPbnbv, {30, 60, 85.25 + i}, 5.5 + i, 20 + i),
                           planner(PlannerKind::kRandom, {30, 50, 70}, 0.25, 0)};
  }
  write_sweep(s, results);
  const std::string md = read_text((dir / "sweep.md").string());
  EXPECT_NE(md.find("# Sweep: resolution"), std::string::npos) << md;
  EXPECT_NE(md.find("| resolution | planner | runs | coverage after the last view (%) |"), std::string::npos) << md;
  // 85.25 -> 85.2 (one decimal), its interval, 5.5 ms, rig time 20 s of which 18 s to 95 %.
  EXPECT_NE(md.find("| 0.03 | pbnbv | 2 | 85.2 [80.0, 90.5] | never | 5.50 ms | 20.0 | 18.0 | 0 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 0.01 | pbnbv | 2 | 86.2 [80.0, 90.5] | never | 6.50 ms | 21.0 | 19.0 | 0 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 0.01 | random | 2 (1 failed) | 70.0 [80.0, 90.5] | never | 0.25 ms | - | - | 0 |"), std::string::npos) << md;
  EXPECT_NE(md.find("--resolution 0.03,0.01"), std::string::npos) << md;
  EXPECT_NE(md.find("--out " + dir.string() + "\n"), std::string::npos) << md;
  const json j = read_json((dir / "sweep.json").string());
  EXPECT_EQ(j["parameters"], json({"resolution"}));
  ASSERT_EQ(j["benches"].size(), 2u);
  EXPECT_EQ(j["benches"][1]["folder"], "resolution=0.01");
  EXPECT_EQ(j["benches"][1]["values"]["resolution"], "0.01");
  EXPECT_EQ(j["benches"][1]["planners"]["pbnbv"]["rig_time_s"], 21.0);
  EXPECT_EQ(j["benches"][1]["planners"]["random"]["rig_time_s"], nullptr);
  EXPECT_EQ(j["benches"][0]["planners"]["pbnbv"]["coverage_by_view"], json({30, 60, 85.25}));
  EXPECT_TRUE(fs::exists(dir / "sweep.png"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace pbnbv::eval
