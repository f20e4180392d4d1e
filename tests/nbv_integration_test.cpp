// Next-best-view scans end to end: the launcher starts the twin and every service (with the
// ellipsoid fitter and the view scorer) as separate processes on a real LCM bus in a private
// network namespace, and PB-NBV chooses every view after the first. Each view must add new
// surface (coverage against the mesh the twin rendered), every planning step must be recorded
// with its figure, and every process must exit cleanly.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "eval/evaluate.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace pbnbv;
using namespace pbnbv::testing;

namespace {

nlohmann::json read_json_file(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

struct NbvScan {
  fs::path out;
  nlohmann::json scan;
  eval::ScanEvaluation eval;
};

NbvScan nbv_scan(const std::string& name, const std::string& options, int views) {
  NbvScan s;
  s.out = fresh_dir(name);
  const std::string cmd = netns_run() + " " + bin_dir() + "/pbnbv scan " + options + " --views " + std::to_string(views) +
                          " --stop-fraction 0 --stop-rule off --sim-speed 20 --no-log --out " + s.out.string();
  const CommandResult r = run_command(cmd);
  EXPECT_EQ(r.exit_code, 0) << cmd << "\n" << r.output;
  std::cout << r.output.substr(r.output.find("coverage after") == std::string::npos ? 0 : r.output.find("coverage after"));
  s.scan = read_json_file(s.out / "scan.json");
  s.eval = eval::evaluate_coverage(s.out);  // the coverage only: no case reads the surface metrics
  // Every process exited cleanly.
  const nlohmann::json procs_json = read_json_file(s.out / "processes.json");
  for (const auto& p : procs_json["processes"]) EXPECT_EQ(p["exit_code"], 0) << p.dump();
  EXPECT_EQ(s.scan["status"]["state"], "done");
  EXPECT_EQ(s.scan["settings"]["planner"], "pbnbv");
  EXPECT_EQ(s.scan["stop"]["rule"], "budget") << s.scan["stop"].dump();
  EXPECT_EQ(s.scan["rig_contacts"], nlohmann::json::array()) << s.scan["rig_contacts"].dump(2);
  return s;
}

// What every next-best-view scan must show: n views, each adding surface, each planned view
// with its record and figure.
void check_views(const NbvScan& s, int views) {
  ASSERT_EQ(s.scan["views"].size(), static_cast<std::size_t>(views));
  ASSERT_EQ(s.eval.coverage_by_view.size(), static_cast<std::size_t>(views));
  for (int i = 1; i < views; ++i) {
    // A view aimed at the frontier covers at least 5 more of the 10,000 surface samples. A
    // gap-filling view (nothing left to aim at: no frontier ellipsoid and no shortlisted
    // candidate's rays reach an unobserved voxel) may add none when what the candidates can see
    // is covered (on the arm, about 88 % of the bunny from view 3-4 on), but never loses any.
    const bool gap_filling = s.scan["views"][i]["plan"]["ranking"].get<std::string>() == "gap_deg";
    EXPECT_GE(s.eval.coverage_by_view[i], s.eval.coverage_by_view[i - 1] + (gap_filling ? 0.0 : 0.05))
        << "view " << i + 1 << " added no new surface: " << s.scan["views"][i]["plan"]["reason"];
  }
  for (int i = 1; i < views; ++i) {
    const auto& plan = s.scan["views"][i]["plan"];
    EXPECT_EQ(plan["outcome"], "view") << plan.dump(2);
    // pbnbv ranks by its combined score (F, the gap to the views taken and rays through the map,
    // each scaled to [0, 1] over the shortlist: 0 to 3) while anything is left to aim at, else it
    // fills the largest gap.
    const std::string reason = plan["reason"].get<std::string>();
    if (plan["ranking"] == "combined") {
      EXPECT_GT(plan["view_quality_px"].get<double>(), 0.0) << reason;
      EXPECT_LE(plan["view_quality_px"].get<double>(), 3.0) << reason;
      EXPECT_NE(reason.find("shortlist"), std::string::npos) << reason;
    } else {
      EXPECT_EQ(plan["ranking"], "gap_deg") << reason;
      EXPECT_NE(reason.find("no shortlisted candidate's rays reach an unobserved voxel"), std::string::npos) << reason;
    }
    EXPECT_EQ(plan["candidates"]["generated"], 800);
    EXPECT_GT(plan["candidates"]["scored"].get<int>(), 100);
    // Without a Frontier voxel nothing is fitted (the ellipsoid service); else both classes are.
    if (reason.find("no frontier ellipsoid") == std::string::npos) {
      EXPECT_GE(plan["ellipsoids"]["frontier_components"].get<int>(), 1);
      EXPECT_GE(plan["ellipsoids"]["occupied_components"].get<int>(), 1);
    }
    for (const char* stage : {"map_update", "ellipsoid_fit", "candidates", "reachability", "scoring"}) {
      EXPECT_TRUE(plan["time_ms"].contains(stage)) << stage;
    }
    ASSERT_TRUE(plan.contains("figure")) << plan.dump(2);
    const cv::Mat figure = cv::imread((s.out / plan["figure"].get<std::string>()).string());
    EXPECT_FALSE(figure.empty()) << plan["figure"];
    // The view reached is the plan's (or one of its alternatives).
    EXPECT_EQ(s.scan["views"][i]["move"]["status"], "reached");
  }
}

}  // namespace

TEST(NbvIntegration, FiveViewBunnyScanOnTheArmRig) {
  const NbvScan s = nbv_scan("nbv-arm", "--object bunny --size 0.2 --rig arm", 5);
  check_views(s, 5);
  EXPECT_GT(s.eval.coverage_by_view.back(), 60.0);
  // Every candidate is accounted for: reachable and scored, unreachable, or near a view taken.
  for (int i = 1; i < 5; ++i) {
    const auto& c = s.scan["views"][i]["plan"]["candidates"];
    EXPECT_EQ(c["scored"].get<int>() + c["unreachable"].get<int>() + c["excluded"].get<int>(), 800) << c.dump();
  }
}

TEST(NbvIntegration, ThreeViewScanOnTheFreeRigFullSphere) {
  // The paper's comparison setup; three views already see nearly everything (a fourth adds
  // nothing measurable on the bunny), so three.
  const NbvScan s = nbv_scan("nbv-free", "--object bunny --size 0.2 --rig free --area full", 3);
  check_views(s, 3);
  // The authors' release reaches 80.2 % on average after three views, a ring of three views
  // about 58 % (pbnbv bench).
  EXPECT_GT(s.eval.coverage_by_view.back(), 85.0);
  EXPECT_EQ(s.scan["views"][1]["plan"]["candidates"]["unreachable"], 0);
}

TEST(NbvIntegration, Ur5eRigScansLikeTheKuka) {
  // The same 5-view PB-NBV scan of the bunny on the KUKA rig (analytic IK) and on the UR5e rig
  // (models/rig_ur5e.xml: parallel-axes IK in the view scorer and the motion executor; the twin plays
  // the UR5e). Both reach the whole candidate hemisphere, so the planner's choices and the
  // coverage must agree within 2 points. Registration off: the twin's kinematic poses are exact,
  // and an ICP rejection (a registration matter, not the rig's) would drop a view from one scan
  // only. A half-size camera (same field of view) keeps it short.
  const std::string common =
      "--object bunny --size 0.2 --registration off --width 640 --height 360 --fx 348 --fy 348 --cx 320 --cy 180";
  const NbvScan kuka = nbv_scan("nbv-kuka", common + " --rig arm", 5);
  const NbvScan ur5e = nbv_scan("nbv-ur5e", common + " --rig-model " + source_dir() + "/models/rig_ur5e.xml", 5);
  check_views(kuka, 5);
  check_views(ur5e, 5);
  const double k = kuka.eval.coverage_by_view.back(), u = ur5e.eval.coverage_by_view.back();
  std::cout << "coverage after 5 views: KUKA " << k << " %, UR5e " << u << " %\n";
  EXPECT_NEAR(u, k, 2.0);
  // The UR5e scan ran with the UR5e: its settings name the model.
  EXPECT_NE(ur5e.scan["settings"].dump().find("rig_ur5e.xml"), std::string::npos);
}
