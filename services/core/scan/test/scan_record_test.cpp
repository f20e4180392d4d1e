// scan.json's entries and the scan folder's clouds, from hand-made answers.
#include "core/scan/scan_record.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/base/units.hpp"
#include "core/io/cloud_file.hpp"
#include "core/io/json.hpp"
#include "core/base/pose.hpp"
#include "error_message.hpp"
#include "file_test_util.hpp"

using namespace pbnbv;
using nlohmann::json;

namespace {

class ScanRecordTest : public pbnbv::testing::TempDirTest {
 protected:
  ScanSettings settings() const {
    ScanSettings s;
    s.scan_id = "record";
    s.views = 4;
    s.voxel_m = 0.002;
    return s;
  }
};

RegisteredCloud registered(bool accepted, const PointCloud& points) {
  RegisteredCloud r;
  r.accepted = accepted;
  r.cloud.points = points;
  return r;
}

TEST_F(ScanRecordTest, AViewEntryHasASectionPerStepReached) {
  ViewRecord v;
  v.view = 2;
  v.option = 1;
  v.requested_object_T_camera = look_at_z_up(Eigen::Vector3d(0.6, 0, 0.3), Eigen::Vector3d::Zero());
  v.failed_moves.push_back({0, Pose::Identity(), MoveStatus::kUnreachable, "no IK solution"});
  MoveResult m;
  m.status = MoveStatus::kReached;
  m.angle_error_rad = kPi / 180;
  m.move_s = 2;
  v.move = m;
  v.move_round_trip_s = 2.5;
  CaptureResult c;
  c.ok = true;
  v.capture = c;
  v.capture_points = 3;
  v.capture_round_trip_s = 1;
  json j = to_json(v);
  EXPECT_EQ(j["view"], 3);  // view 2 (0-based) is the third: counted from 1 in the file
  EXPECT_EQ(j["option"], 1);
  EXPECT_NEAR(j["requested_object_T_camera"]["position_m"][0].get<double>(), 0.6, 1e-12);
  EXPECT_EQ(j["failed_moves"][0]["status"], "unreachable");
  EXPECT_EQ(j["move"]["status"], "reached");
  EXPECT_NEAR(j["move"]["angle_error_deg"].get<double>(), 1.0, 1e-12);
  EXPECT_EQ(j["move"]["joint_position_rad"].size(), 6u);
  EXPECT_EQ(j["time_s"]["move"], 2.0);
  EXPECT_EQ(j["time_s"]["move_round_trip"], 2.5);
  EXPECT_EQ(j["capture"]["num_points"], 3);
  EXPECT_EQ(j["time_s"]["capture_round_trip"], 1.0);
  EXPECT_FALSE(j.contains("registration"));
  EXPECT_FALSE(j.contains("map"));
  EXPECT_FALSE(j.contains("frame_file"));
  EXPECT_FALSE(j.contains("plan"));

  ViewRecord lost;
  lost.move_unanswered = true;
  j = to_json(lost);
  EXPECT_EQ(j["move"], json({{"status", "no_answer"}, {"reason", "no MOVE_RESULT from the motion executor"}}));
  EXPECT_FALSE(j.contains("time_s"));
}

// scan.json counts views from 1 (format 2), as view_001 is the first view's file; the record keeps
// them 0-based. A view 0 is refused naming the field and the range.
TEST_F(ScanRecordTest, TheFirstViewIsWrittenAsView1AndReadBackAs0) {
  ViewRecord first;
  first.view = 0;
  const json j = to_json(first);
  EXPECT_EQ(j["view"], 1);
  EXPECT_EQ(view_record_from_json(j, "DIR/scan.json views[0]").view, 0);
  ViewRecord last;
  last.view = 999;
  EXPECT_EQ(to_json(last)["view"], 1000);
  EXPECT_EQ(view_record_from_json(to_json(last), "DIR/scan.json views[999]").view, 999);
  pbnbv::testing::expect_error([] { view_record_from_json(json{{"view", 0}}, "DIR/scan.json views[0]"); },
                               "DIR/scan.json views[0] view = 0 is not a whole number in 1..1000");
  pbnbv::testing::expect_error([] { view_record_from_json(json{{"view", 1001}}, "DIR/scan.json views[0]"); },
                               "DIR/scan.json views[0] view = 1001 is not a whole number in 1..1000");
}

TEST_F(ScanRecordTest, APlanEntryTimesThePlannerStepAsThePaperDoes) {
  PlanRecord p;
  p.plan.iteration = 4;
  p.plan.planner = PlannerKind::kPbnbv;
  p.plan.outcome = PlanOutcome::kView;
  p.plan.plan_s = 0.25;
  p.plan.first_quality = std::nan("");
  p.map_of_view = 3;
  p.map_update_s = 0.5;
  EXPECT_EQ(planner_step_ms(p), 750.0);  // no ellipsoids: map update + view selection
  EllipsoidSetSummary e;
  e.fit_s = 0.125;
  p.ellipsoids = e;
  EXPECT_EQ(planner_step_ms(p), 875.0);
  const json j = to_json(p);
  EXPECT_EQ(j["planner_step_ms"], 875.0);
  EXPECT_EQ(j["time_ms"]["ellipsoid_fit"], 125.0);
  EXPECT_EQ(j["figure"], "plans/view_005.png");  // iteration 4 is the fifth view
  EXPECT_EQ(j["outcome"], "view");
  EXPECT_EQ(j["map_of_view"], 4);  // counted from 1 as "view"
  p.map_of_view = -1;
  EXPECT_EQ(to_json(p)["map_of_view"], 0);  // not known
  EXPECT_NE(j.dump().find("\"first_quality_px\":null"), std::string::npos) << "NaN is written as null";
  EXPECT_EQ(j["ellipsoids"]["list"].size(), 0u);
}

TEST_F(ScanRecordTest, TheStatusAndStopAreWrittenWithTheViews) {
  ScanRecord record(dir_, settings());
  record.set_ring_plan(0.8, 30);
  ViewRecord v;
  record.add_view(v, 1, 2.5);
  json j = read_json((dir_ / "scan.json").string());
  EXPECT_EQ(j["status"], json({{"state", "running"}, {"message", ""}, {"views_done", 1}, {"views_planned", 4},
                               {"elapsed_s", 2.5}, {"num_points", 0}, {"next_request_id", 1}, {"answers_refused", 0}}));
  EXPECT_EQ(j["views"].size(), 1u);
  EXPECT_EQ(j["plan"]["planner"], "ring");
  EXPECT_FALSE(j.contains("stop"));
  record.set_stop({"view budget reached (--views 4)", 1, "budget", {}});
  record.write("done", "scan complete", 1, 3.0);
  j = read_json((dir_ / "scan.json").string());
  EXPECT_EQ(j["status"]["state"], "done");
  EXPECT_EQ(j["stop"]["rule"], "budget");
  EXPECT_EQ(j["settings"]["scan_id"], "record");
}

}  // namespace

// A view's files and model figures are the registration service's answer, said as it said them.
TEST_F(ScanRecordTest, AViewEntrySaysTheFilesAndNewSurfaceTheRegistrationWrote) {
  ViewRecord v;
  v.view = 0;
  RegisteredCloud r = registered(true, {});
  r.cloud.object_T_camera = look_at_z_up(Eigen::Vector3d(0.7, 0, 0), Eigen::Vector3d::Zero());
  r.frame_file = "frames/view_001.ply";
  r.depth_file = "depth/view_001.png";
  r.normals_from_depth = true;
  r.new_surface = NewSurface{200, 50, 1000, 0.005};
  r.accumulate_s = 0.25;
  v.registration = r;
  json j = to_json(v);
  EXPECT_EQ(j["frame_file"], "frames/view_001.ply");
  EXPECT_EQ(j["depth_file"], "depth/view_001.png");
  EXPECT_EQ(j["normals"], "depth image");
  EXPECT_EQ(j["merged"], true);
  EXPECT_NEAR(j["camera_pose"]["position_m"][0].get<double>(), 0.7, 1e-12);
  EXPECT_EQ(j["new_surface"]["percent_of_model"], 5.0);  // 50 new points of a model of 1000
  EXPECT_EQ(j["new_surface"]["percent_of_frame"], 25.0);
  EXPECT_EQ(j["time_s"]["accumulate"], 0.25);
  // Rejected, no folder: not merged, no files, no figure.
  v.registration = registered(false, {});
  j = to_json(v);
  EXPECT_EQ(j["merged"], false);
  EXPECT_FALSE(j.contains("frame_file"));
  EXPECT_FALSE(j.contains("new_surface"));
}

TEST_F(ScanRecordTest, TheMeshEntrySaysWhatTheMeshIs) {
  MeshSummary m;
  m.files = {"mesh.ply", "mesh.obj"};
  m.triangles = 12;
  m.vertices = 8;
  m.watertight = true;
  m.volume_m3 = 0.001;
  m.voxel_m = 0.001;
  m.truncation_m = 0.004;
  json j = to_json(m);
  EXPECT_EQ(j["file"], "mesh.ply");
  EXPECT_EQ(j["also"], json::array({"mesh.obj"}));
  EXPECT_EQ(j["method"], "tsdf");
  EXPECT_EQ(j["triangles"], 12);
  EXPECT_EQ(j["volume_m3"], 0.001);
  EXPECT_EQ(j["settings"]["truncation_m"], 0.004);
  m.watertight = false;
  m.volume_m3.reset();
  m.tsdf = false;
  m.poisson_depth = 8;
  j = to_json(m);
  EXPECT_TRUE(j["volume_m3"].is_null());
  EXPECT_EQ(j["method"], "poisson");
  EXPECT_EQ(j["settings"], json({{"poisson_depth", 8}}));
}
