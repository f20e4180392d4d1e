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
  v.failed_moves.push_back({0, Pose::Identity(), MoveStatus::kUnreachable, "no IK solution", 7, 0, ""});
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

TEST_F(ScanRecordTest, APlanEntryTimesThePlannerStepAsTheScanWaitedForIt) {
  // The scorer got the request, checked reachability (0.1875 s) while the ellipsoid fitter worked
  // (0.125 s), had the ellipsoids by then (wait 0.1875 s) and ranked for 0.0625 s: view selection
  // 0.25 s. The scan waited map update 0.5 + 0.1875 + 0.0625 = 0.75 s; the parts' sum, with the
  // fit that ran beside the check, is 0.875 s.
  PlanRecord p;
  p.plan.iteration = 1;
  p.plan.planner = PlannerKind::kPbnbv;
  p.plan.outcome = PlanOutcome::kView;
  p.plan.first_quality = std::nan("");
  p.map_update_s = 0.5;
  p.plan.reachability_s = 0.1875;
  p.plan.wait_s = 0.1875;
  p.plan.plan_s = 0.25;
  EllipsoidSetSummary e;
  e.fit_s = 0.125;
  p.ellipsoids = e;
  EXPECT_EQ(planner_step_ms(p), 875.0);
  EXPECT_EQ(planner_critical_ms(p), 750.0);
  EXPECT_EQ(to_json(p)["planner_critical_ms"], 750.0);
  // The fit outlasting the check: the scorer waited for the ellipsoids 0.0625 s more.
  p.plan.wait_s = 0.25;
  EXPECT_EQ(planner_critical_ms(p), 812.5);
  // A wait shorter than the check it holds is not a scorer's record: not known.
  p.plan.wait_s = 0.125;
  EXPECT_TRUE(std::isnan(planner_critical_ms(p)));
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
  // Without the scorer's wait the step as the scan waited for it is not known.
  EXPECT_TRUE(std::isnan(planner_critical_ms(p)));
  EXPECT_FALSE(j.contains("planner_critical_ms"));
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

// The rig's contacts: per move (and failed move) its request id, count and last text; top-level
// rig_contacts lists the moves with any, a failed move that ended its view (also its "move")
// once, a move whose rig could not tell (-1) not at all. Read back into the same types; a
// rig_contacts that disagrees with the views, or a text without a count, is refused naming it.
TEST_F(ScanRecordTest, TheRigsContactsAreRecordedPerMoveAndListedOnce) {
  ScanRecord record(dir_, settings());
  record.set_ring_plan(0.8, 30);
  const std::string table = "contact: camera_optical / table, 1.4 mm deep, at rig time 12.345 s, during command 11";
  const std::string pedestal = "contact: link_4 / pedestal, 0.6 mm deep, at rig time 20.000 s, during command 13";
  auto result = [](int64_t request, MoveStatus status, int32_t contacts, const std::string& text) {
    MoveResult m;
    m.request_id = request;
    m.status = status;
    m.contacts = contacts;
    m.contact = text;
    return m;
  };
  ViewRecord v0;  // a contact stopped its only move: the view failed
  v0.view = 0;
  const MoveResult stopped = result(11, MoveStatus::kTimedOut, 1, table);
  v0.failed_moves.push_back({0, Pose::Identity(), stopped.status, "the arm driver reported a contact fault", 11, 1, table});
  v0.move = stopped;
  record.add_view(v0, 0, 1.0);
  ViewRecord v1;  // an unreachable option, then an alternative reached with two contacts on the way
  v1.view = 1;
  v1.failed_moves.push_back({0, Pose::Identity(), MoveStatus::kUnreachable, "no IK solution", 12, 0, ""});
  v1.option = 1;
  v1.move = result(13, MoveStatus::kReached, 2, pedestal);
  record.add_view(v1, 1, 2.0);
  ViewRecord v2;  // a rig that cannot tell
  v2.view = 2;
  v2.option = 0;
  v2.move = result(14, MoveStatus::kReached, -1, "");
  record.add_view(v2, 2, 3.0);

  json j = read_json((dir_ / "scan.json").string());
  EXPECT_EQ(j["rig_contacts"], json::array({{{"view", 1}, {"request_id", 11}, {"contacts", 1}, {"contact", table}},
                                            {{"view", 2}, {"request_id", 13}, {"contacts", 2}, {"contact", pedestal}}}));
  EXPECT_EQ(j["views"][0]["failed_moves"][0]["contacts"], 1);
  EXPECT_EQ(j["views"][0]["move"]["request_id"], 11);
  EXPECT_EQ(j["views"][2]["move"]["contacts"], -1);
  const RecordedScan r = read_scan_record(dir_);
  ASSERT_EQ(r.views.size(), 3u);
  EXPECT_EQ(r.views[0].failed_moves[0].request_id, 11);
  EXPECT_EQ(r.views[0].failed_moves[0].contact, table);
  EXPECT_EQ(r.views[1].failed_moves[0].contacts, 0);
  EXPECT_EQ(r.views[1].move->contacts, 2);
  EXPECT_EQ(r.views[1].move->request_id, 13);
  EXPECT_EQ(r.views[2].move->contacts, -1);
  const std::vector<RigContactRecord> listed = rig_contacts(r.views);
  ASSERT_EQ(listed.size(), 2u);
  EXPECT_EQ(listed[1], (RigContactRecord{1, 13, 2, pedestal}));
  EXPECT_EQ(rig_contact_events(listed), 3);
  EXPECT_EQ(to_string(listed[0]), "view 1 (request 11): " + table);
  EXPECT_EQ(to_string(listed[1]), "view 2 (request 13, 2 contacts): " + pedestal);
  EXPECT_EQ(to_json(r)["rig_contacts"], j["rig_contacts"]) << "written again as read";

  const std::string where = (dir_ / "scan.json").string();
  json bad = j;
  bad["rig_contacts"][1]["contacts"] = 1;
  pbnbv::testing::expect_error([&] { recorded_scan_from_json(bad, where); },
                               where + " rig_contacts[1] is not what the views record for it (view 2, request 13, 2 contacts");
  bad = j;
  bad["rig_contacts"].erase(1);
  pbnbv::testing::expect_error([&] { recorded_scan_from_json(bad, where); },
                               where + " rig_contacts lists 1 moves with contacts, the views have 2");
  bad = j;
  bad["rig_contacts"][0]["view"] = 0;
  pbnbv::testing::expect_error([&] { recorded_scan_from_json(bad, where); }, "rig_contacts[0] view = 0 is not a whole number in 1..1000");
  bad = j;
  bad["views"][2]["move"]["contact"] = "link_6 / platter";
  pbnbv::testing::expect_error([&] { recorded_scan_from_json(bad, where); },
                               where + " views[2] view 3 move contact is given with contacts -1");
  bad = j;
  bad["views"][1]["move"]["contacts"] = -2;
  pbnbv::testing::expect_error([&] { recorded_scan_from_json(bad, where); }, "move contacts = -2 is not a whole number in -1..");
}

// Rig time from the messages, by hand: a move commanded at rig clock 5.0 s, within tolerance at
// 7.0 s, settled at 7.5 s (rig_motion_s 2.5) moves for 2.0 s and settles for 0.5 s on the rig's
// clock; the capture and the wait for the next command are wall time.
TEST_F(ScanRecordTest, RigTimeSplitsTheMoveOnTheRigClockAndTimesTheRestOnTheWallClock) {
  MoveResult m;
  m.rig_motion_s = 2.5;
  m.settled_utime = 7500000;
  m.within_tolerance_utime = 7000000;
  MoveRigTime t = move_rig_time(m);
  EXPECT_DOUBLE_EQ(t.motion_s, 2.0);
  EXPECT_DOUBLE_EQ(t.settle_s, 0.5);
  m.within_tolerance_utime = 0;  // never within tolerance (timed out): all motion
  t = move_rig_time(m);
  EXPECT_DOUBLE_EQ(t.motion_s, 2.5);
  EXPECT_EQ(t.settle_s, 0.0);
  m.within_tolerance_utime = 4000000;  // before the command (7.5 - 2.5 = 5.0 s): not a fit
  EXPECT_TRUE(std::isnan(move_rig_time(m).motion_s));
  m.within_tolerance_utime = 8000000;  // after settling
  EXPECT_TRUE(std::isnan(move_rig_time(m).settle_s));
  m.within_tolerance_utime = 7000000;
  m.rig_motion_s = -1;
  EXPECT_TRUE(std::isnan(move_rig_time(m).motion_s));

  // The settled move's answer came at 20.0 s, the cloud at 20.5 s after 0.125 s of processing
  // in the camera service: the frame arrived 0.375 s after the answer.
  CaptureResult c;
  c.process_s = 0.125;
  EXPECT_EQ(capture_wait_s(20.0, 20.5, c), 0.375);
  c.process_s = 0.75;  // more processing than the whole wait: figures that do not fit
  EXPECT_TRUE(std::isnan(capture_wait_s(20.0, 20.5, c)));

  // The rig waited from 10.0 s (coordinator's clock) until the next command: its answer came at
  // 16.0 s after 4.0 s of moving and 0.5 s of settling (the executor's wall time): 1.5 s.
  MoveResult next;
  next.move_s = 4.0;
  next.settle_s = 0.5;
  EXPECT_DOUBLE_EQ(compute_wait_s(10.0, 16.0, next), 1.5);
  EXPECT_TRUE(std::isnan(compute_wait_s(10.0, 14.0, next)));  // a move longer than the wait: not a fit

  const RigTime r{19.84, 1.2, 0.4, 2.7};
  EXPECT_NEAR(r.total_s(), 24.14, 1e-12);
  EXPECT_EQ(rig_time_text(r), "24.1 s (motion 19.8, settle 1.2, capture 0.4, compute 2.7)");
  EXPECT_EQ(rig_time_text(RigTime{1, 2, 3, RigTime::kUnset}), "- s (motion 1.0, settle 2.0, capture 3.0, compute -)");
}

// Each view's rig_time_s and their sums at the top of scan.json round-trip through the reader;
// a total that is not the sum of its parts, a negative part, or top-level sums that are not the
// views' are refused naming the file, the view and the field.
TEST_F(ScanRecordTest, RigTimeIsWrittenPerViewAndSummedAndReadBackChecked) {
  ScanRecord record(dir_, settings());
  record.set_ring_plan(0.8, 30);
  ViewRecord a;
  a.view = 0;
  a.move = MoveResult{};
  a.move_round_trip_s = 1;
  a.rig_time = RigTime{2.0, 0.5, 0.125, 1.5};
  record.add_view(a, 1, 5.0);
  ViewRecord b;
  b.view = 1;
  b.move = MoveResult{};
  b.move_round_trip_s = 1;
  b.rig_time = RigTime{1.0, 0.25, 0.0, RigTime::kUnset};  // compute not known yet
  record.add_view(b, 1, 6.0);
  json j = read_json((dir_ / "scan.json").string());
  EXPECT_EQ(j["views"][0]["rig_time_s"], json({{"motion", 2.0}, {"settle", 0.5}, {"capture", 0.125}, {"compute", 1.5}, {"total", 4.125}}));
  EXPECT_TRUE(j["views"][1]["rig_time_s"]["compute"].is_null());
  EXPECT_TRUE(j["views"][1]["rig_time_s"]["total"].is_null());
  // Sums of what is known: 3.0 + 0.75 + 0.125 + 1.5 = 5.375; one view not measured in full.
  EXPECT_EQ(j["rig_time_s"], json({{"motion", 3.0}, {"settle", 0.75}, {"capture", 0.125}, {"compute", 1.5},
                                   {"total", 5.375}, {"views", 2}, {"views_incomplete", 1}}));
  // The wait of view 2 comes with the next move's answer (or the scan's end).
  record.set_compute_wait(1, 0.25);
  record.set_compute_wait(7, 9.0);  // no such view: nothing
  record.write("done", "scan complete", 2, 7.0);
  j = read_json((dir_ / "scan.json").string());
  EXPECT_EQ(j["views"][1]["rig_time_s"]["total"], 1.5);
  EXPECT_EQ(j["rig_time_s"]["total"], 5.625);
  EXPECT_EQ(j["rig_time_s"]["views_incomplete"], 0);

  const RecordedScan back = read_scan_record(dir_);
  ASSERT_EQ(back.views.size(), 2u);
  ASSERT_TRUE(back.views[0].rig_time);
  EXPECT_EQ(back.views[0].rig_time->motion_s, 2.0);
  EXPECT_EQ(back.views[0].rig_time->settle_s, 0.5);
  EXPECT_EQ(back.views[0].rig_time->capture_s, 0.125);
  EXPECT_EQ(back.views[0].rig_time->compute_s, 1.5);
  EXPECT_EQ(back.views[1].rig_time->compute_s, 0.25);
  EXPECT_EQ(to_json(back)["rig_time_s"], j["rig_time_s"]);
  const RigTimeSum sum = sum_rig_time(back.views);
  EXPECT_EQ(sum.sum.total_s(), 5.625);
  EXPECT_EQ(sum.views, 2);

  const std::string file = (dir_ / "scan.json").string();
  json bad = j;
  bad["views"][0]["rig_time_s"]["total"] = 4.0;
  pbnbv::testing::expect_error([&] { recorded_scan_from_json(bad, file); },
                               file + " views[0] view 1 rig_time_s total is 4, not motion + settle + capture + compute = 4.125");
  bad = j;
  bad["views"][1]["rig_time_s"]["settle"] = -0.25;
  pbnbv::testing::expect_error([&] { recorded_scan_from_json(bad, file); },
                               file + " views[1] view 2 rig_time_s settle is not a duration in seconds (0..1e9) nor null");
  bad = j;
  bad["rig_time_s"]["capture"] = 0.5;
  bad["rig_time_s"]["total"] = 6.0;
  pbnbv::testing::expect_error([&] { recorded_scan_from_json(bad, file); }, file + " rig_time_s capture is 0.5, not the views' sum 0.125");
  bad = j;
  bad["rig_time_s"]["views"] = 3;
  pbnbv::testing::expect_error([&] { recorded_scan_from_json(bad, file); }, file + " rig_time_s views is 3, not the 2 views with a rig_time_s");
  // A record written before rig time was recorded has none: read as none.
  bad = j;
  bad.erase("rig_time_s");
  bad["views"][0].erase("rig_time_s");
  bad["views"][1].erase("rig_time_s");
  const RecordedScan old = recorded_scan_from_json(bad, file);
  EXPECT_FALSE(old.views[0].rig_time);
  EXPECT_EQ(sum_rig_time(old.views).views, 0);
}

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

}  // namespace
