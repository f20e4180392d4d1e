// A replay against its recording, from two hand-made records: every decision compared (accepted,
// registered pose, voxel counts, planned view).
#include "core/scan/scan_comparison.hpp"

#include <gtest/gtest.h>

#include "core/base/units.hpp"
#include "core/io/json.hpp"
#include "error_message.hpp"

using namespace pbnbv;
using nlohmann::json;

namespace {

Pose pose(double x, double y, double z, double angle_z_rad = 0) {
  Pose p = Pose::Identity();
  p.translation() = Eigen::Vector3d(x, y, z);
  p.linear() = Eigen::AngleAxisd(angle_z_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return p;
}

VoxelMapSummary voxels(int occupied, int frontier) {
  VoxelMapSummary m;
  m.num_occupied = occupied;
  m.num_frontier = frontier;
  m.num_unknown = 300;
  m.num_empty = 400;
  m.num_none = 5;
  return m;
}

RegisteredCloud registration(bool accepted, double translation_mm, double rotation_deg, const Pose& registered) {
  RegisteredCloud r;
  r.accepted = accepted;
  r.translation_m = translation_mm * 1e-3;
  r.rotation_deg = rotation_deg;
  r.cloud.object_T_camera = registered;
  return r;
}

// A two-view record: view 1 the initial view, view 2 planned at `planned`, reached at option 1
// after option 0 failed.
RecordedScan record(const Pose& planned, int occupied_2, bool accepted_2) {
  ViewRecord v1;
  v1.view = 0;
  v1.initial_view = true;
  v1.option = 0;
  v1.requested_object_T_camera = pose(0.9, 0, 0.3);
  v1.registration = registration(true, 0, 0, pose(0.9, 0, 0.3));
  v1.map = voxels(20, 10);
  ViewRecord v2;
  v2.view = 1;
  v2.plan = PlanRecord{};
  v2.plan->plan.outcome = PlanOutcome::kView;
  v2.plan->plan.object_T_camera = planned;
  v2.failed_moves = {{0, planned, MoveStatus::kUnreachable, "below the table"}};
  v2.option = 1;
  v2.requested_object_T_camera = pose(0, 0.9, 0.3);
  v2.registration = registration(accepted_2, 1.5, 0.25, pose(0, 0.9015, 0.3));
  v2.map = voxels(occupied_2, 8);
  RecordedScan r;
  r.views = {v1, v2};
  return r;
}

}  // namespace

TEST(ScanComparison, TheSameRecordTwiceHasTheSameDecisions) {
  const RecordedScan r = record(pose(0.1, 0.2, 0.9), 30, true);
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
  const RecordedScan a = record(pose(0.1, 0.2, 0.9), 30, true);
  const RecordedScan b = record(pose(0.102, 0.2, 0.9, 0.001), 31, false);
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
  RecordedScan shorter = a;
  shorter.views.pop_back();
  EXPECT_EQ(compare_scans(a, shorter)["differences"].back(), "view 2: only in the original");
}
