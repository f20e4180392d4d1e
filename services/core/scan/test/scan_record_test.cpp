// scan.json's entries and the scan folder's clouds, from hand-made answers.
#include "core/scan/scan_record.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/base/units.hpp"
#include "core/io/cloud_file.hpp"
#include "core/io/json.hpp"
#include "core/base/pose.hpp"
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

TEST_F(ScanRecordTest, AcceptedViewsAreMergedAndDownsampledRejectedOnesOnlyKeptInFrames) {
  ScanRecord record(dir_, settings());
  EXPECT_TRUE(std::filesystem::is_directory(dir_ / "frames"));
  // Two points 0.5 mm apart fall into one 2 mm voxel: merged into their centroid.
  ViewRecord v0;
  v0.view = 0;
  record.accumulate(registered(true, {Eigen::Vector3f(0.0105f, 0.0105f, 0.0105f), Eigen::Vector3f(0.5f, 0, 0)}), v0);
  ViewRecord v1;
  v1.view = 1;
  record.accumulate(registered(true, {Eigen::Vector3f(0.0110f, 0.0105f, 0.0105f)}), v1);
  ViewRecord v2;
  v2.view = 2;
  record.accumulate(registered(false, {Eigen::Vector3f(-0.3f, 0, 0), Eigen::Vector3f(-0.2f, 0, 0)}), v2);
  EXPECT_EQ(v0.frame_file, "frames/view_001.ply");  // files count views from 1
  EXPECT_EQ(v2.frame_file, "frames/view_003.ply");
  EXPECT_TRUE(v1.merged);
  EXPECT_FALSE(v2.merged);
  EXPECT_EQ(read_ply((dir_ / "frames/view_003.ply").string()).size(), 2u);
  const PointCloud cloud = read_ply((dir_ / "cloud.ply").string());
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(record.num_points(), 2u);
  bool centroid = false;
  for (const auto& p : cloud) centroid |= std::abs(p.x() - 0.01075f) < 1e-6f;
  EXPECT_TRUE(centroid) << "the two close points become their centroid";
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
  c.points.resize(3);
  v.capture = c;
  v.capture_round_trip_s = 1;
  json j = to_json(v);
  EXPECT_EQ(j["view"], 2);
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
  EXPECT_EQ(j["map_of_view"], 3);
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

// A wall 0.5 m in front of a 64 x 48 camera (fx = fy = 50 px) looking along the object's -x from
// x = 0.7: its points come back with normals facing the camera, +x (from the depth image's
// neighbourhood; k-NN when the frame is gone), the camera pose in the PLY header and scan.json,
// and the depth image's file with the camera model beside it.
TEST_F(ScanRecordTest, FramesCarryNormalsTowardsTheCameraItsPoseAndTheDepthImage) {
  ScanRecord record(dir_, settings());
  const Pose pose = look_at_z_up(Eigen::Vector3d(0.7, 0, 0), Eigen::Vector3d::Zero());
  DepthFrame frame;
  frame.seq = 7;
  frame.intrinsics = CameraIntrinsics{64, 48, 50.0, 50.0, 32.0, 24.0};
  frame.depth_m.assign(64 * 48, 0.5f);
  RegisteredCloud r = registered(true, {});
  for (int v = 2; v < 46; v += 4) {
    for (int u = 2; u < 62; u += 4) {
      r.cloud.points.push_back((pose * back_project(frame.intrinsics, u, v, 0.5)).cast<float>());
    }
  }
  r.cloud.object_T_camera = pose;
  r.cloud.depth_frame_seq = 7;
  std::vector<std::string> written;
  record.set_depth_image_writer([&](const std::vector<float>& d, int w, int h, const std::string& path) {
    EXPECT_EQ(d.size(), static_cast<std::size_t>(w * h));
    written.push_back(path);
  });
  record.keep_depth_frame(frame);
  ViewRecord v0;
  v0.view = 0;
  v0.registration = r;
  record.accumulate(r, v0);
  EXPECT_EQ(v0.normals, "depth image");
  EXPECT_EQ(v0.depth_file, "depth/view_001.png");
  ASSERT_EQ(written.size(), 1u);
  EXPECT_EQ(written[0], (dir_ / "depth" / "view_001.png").string());
  CloudExtras extras;
  const PointCloud points = read_ply((dir_ / "frames/view_001.ply").string(), extras);
  ASSERT_EQ(points.size(), r.cloud.points.size());
  ASSERT_EQ(extras.normals.size(), points.size());
  for (const auto& n : extras.normals) EXPECT_NEAR(n.x(), 1.0f, 1e-5f) << n.transpose();  // the wall faces +x
  ASSERT_EQ(extras.camera_poses.size(), 1u);
  EXPECT_TRUE(extras.camera_poses[0].isApprox(pose, 1e-6));
  CloudExtras merged;
  read_ply((dir_ / "cloud.ply").string(), merged);
  ASSERT_FALSE(merged.normals.empty());
  for (const auto& n : merged.normals) EXPECT_NEAR(n.x(), 1.0f, 1e-5f);
  ASSERT_EQ(merged.camera_poses.size(), 1u);
  // The camera model beside the image, as the frame gave it.
  const json k = read_json((dir_ / "depth" / "view_001.json").string());
  EXPECT_EQ(k["image"], "view_001.png");
  EXPECT_EQ(k["width"], 64);
  EXPECT_EQ(k["height"], 48);
  EXPECT_EQ(k["fx"], 50.0);
  EXPECT_EQ(k["cy"], 24.0);
  EXPECT_EQ(k["depth_scale"], 1000);
  EXPECT_TRUE(pose_from_json(k["object_T_camera"], "object_T_camera").isApprox(pose, 1e-12));
  const json j = to_json(v0);
  EXPECT_EQ(j["depth_file"], "depth/view_001.png");
  EXPECT_NEAR(j["camera_pose"]["position_m"][0].get<double>(), 0.7, 1e-12);
  // The frame gone: normals from the neighbours, facing the camera all the same.
  ViewRecord v1;
  v1.view = 1;
  r.cloud.depth_frame_seq = 8;
  record.accumulate(r, v1);
  EXPECT_EQ(v1.normals, "neighbours");
  EXPECT_TRUE(v1.depth_file.empty());
  read_ply((dir_ / "frames/view_002.ply").string(), extras);
  for (const auto& n : extras.normals) EXPECT_NEAR(n.x(), 1.0f, 1e-4f);
}
