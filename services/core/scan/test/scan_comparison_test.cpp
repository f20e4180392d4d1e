// A replay against its recording, from two hand-written scan.json records: the poses a replay
// moves to, and every decision compared (accepted, registered pose, voxel counts, planned view).
#include "core/scan/scan_comparison.hpp"

#include <gtest/gtest.h>

#include "core/base/units.hpp"
#include "core/io/json.hpp"
#include "error_message.hpp"

using namespace pbnbv;
using nlohmann::json;

namespace {

json pose(double x, double y, double z, double angle_z_rad = 0) {
  Pose p = Pose::Identity();
  p.translation() = Eigen::Vector3d(x, y, z);
  p.linear() = Eigen::AngleAxisd(angle_z_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return to_json(p);
}

json voxels(int occupied, int frontier) {
  return {{"occupied", occupied}, {"frontier", frontier}, {"unknown", 300}, {"empty", 400}, {"none", 5}};
}

// A two-view record: view 1 the initial view, view 2 planned at `planned`, reached at option 1
// after option 0 failed.
json record(const json& planned, int occupied_2, bool accepted_2) {
  json v1 = {{"view", 0},
             {"plan", {{"planner", "initial view"}}},
             {"option", 0},
             {"requested_object_T_camera", pose(0.9, 0, 0.3)},
             {"registration", {{"accepted", true}, {"translation_mm", 0.0}, {"rotation_deg", 0.0},
                               {"registered_object_T_camera", pose(0.9, 0, 0.3)}}},
             {"map", {{"voxels", voxels(20, 10)}}},
             {"merged", true}};
  json v2 = {{"view", 1},
             {"plan", {{"outcome", "view"}, {"object_T_camera", planned}}},
             {"failed_moves", {{{"option", 0}, {"status", "unreachable"}, {"object_T_camera", planned}}}},
             {"option", 1},
             {"requested_object_T_camera", pose(0, 0.9, 0.3)},
             {"registration", {{"accepted", accepted_2}, {"translation_mm", 1.5}, {"rotation_deg", 0.25},
                               {"registered_object_T_camera", pose(0, 0.9015, 0.3)}}},
             {"map", {{"voxels", voxels(occupied_2, 8)}}},
             {"merged", accepted_2}};
  return {{"views", {v1, v2}}};
}

}  // namespace

TEST(ScanComparison, TheRecordedPosesAreEachViewsFailedMovesThenTheOneReached) {
  const std::vector<std::vector<Pose>> a = recorded_attempts(record(pose(0.1, 0.2, 0.9), 30, true), "scan.json");
  ASSERT_EQ(a.size(), 2u);
  ASSERT_EQ(a[0].size(), 1u);
  EXPECT_TRUE(a[0][0].translation().isApprox(Eigen::Vector3d(0.9, 0, 0.3)));
  ASSERT_EQ(a[1].size(), 2u);
  EXPECT_TRUE(a[1][0].translation().isApprox(Eigen::Vector3d(0.1, 0.2, 0.9)));
  EXPECT_TRUE(a[1][1].translation().isApprox(Eigen::Vector3d(0, 0.9, 0.3)));
  json bad = record(pose(0.1, 0.2, 0.9), 30, true);
  bad["views"][1]["requested_object_T_camera"].erase("quat_wxyz");
  pbnbv::testing::expect_error([&] { recorded_attempts(bad, "orig/scan.json"); }, "orig/scan.json view 2 requested pose");
}

TEST(ScanComparison, TheSameRecordTwiceHasTheSameDecisions) {
  const json r = record(pose(0.1, 0.2, 0.9), 30, true);
  const json c = compare_scans(r, r);
  EXPECT_TRUE(c["same_decisions"].get<bool>()) << c.dump(2);
  EXPECT_EQ(c["differences"], json::array());
  ASSERT_EQ(c["views"].size(), 2u);
  EXPECT_EQ(c["views"][0]["plan"]["same"], true);  // no plan in either (the initial view)
  EXPECT_EQ(c["views"][1]["plan"]["position_m"], 0.0);
  EXPECT_EQ(c["views"][1]["correction"]["replay"], json({{"translation_mm", 1.5}, {"rotation_deg", 0.25}}));
  const std::string table = comparison_table(c);
  EXPECT_NE(table.find("same decisions in every view"), std::string::npos) << table;
  EXPECT_NE(table.find("1.50/0.25 -> 1.50/0.25"), std::string::npos) << table;
}

TEST(ScanComparison, EachDifferingDecisionIsNamedWithItsView) {
  // The replay plans view 2 2 mm further along x and turned 0.001 rad; one more occupied voxel;
  // registration rejects view 2.
  const json a = record(pose(0.1, 0.2, 0.9), 30, true);
  const json b = record(pose(0.102, 0.2, 0.9, 0.001), 31, false);
  const json c = compare_scans(a, b);
  EXPECT_FALSE(c["same_decisions"].get<bool>());
  EXPECT_EQ(c["differences"], json({"view 2: accepted differs", "view 2: merged differs", "view 2: voxels differs",
                                     "view 2: plan differs"}));
  const json& plan = c["views"][1]["plan"];
  EXPECT_NEAR(plan["position_m"].get<double>(), 0.002, 1e-12);
  EXPECT_NEAR(plan["angle_deg"].get<double>(), rad_to_deg(0.001), 1e-9);
  // 1 um and 1 urad apart is the same view; 2 um is not.
  EXPECT_TRUE(compare_scans(a, record(pose(0.1 + 0.9e-6, 0.2, 0.9, 0.9e-6), 30, true))["same_decisions"].get<bool>());
  EXPECT_FALSE(compare_scans(a, record(pose(0.1 + 2e-6, 0.2, 0.9), 30, true))["same_decisions"].get<bool>());
  // A view only one of them has.
  json shorter = a;
  shorter["views"].erase(1);
  EXPECT_EQ(compare_scans(a, shorter)["differences"].back(), "view 2: only in the original");
}
