// Bad input never crashes or hangs a process: malformed bytes and out-of-contract messages on
// every channel a service subscribes to are rejected (counted in its heartbeat, logged with
// the channel and the reason) and the service keeps answering valid requests; an unreachable
// view is reported unreachable with a reason; a missing or malformed mesh, or a mistyped
// option, stops the launcher with a message naming it before any process starts.
// Runs inside a private network namespace (see CMakeLists.txt).
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <thread>

#include "bus/convert.hpp"
#include "core/geometry/mesh.hpp"
#include "core/base/pose.hpp"
#include "core/io/json.hpp"
#include "core/io/mesh_file.hpp"
#include "core/rig/rig.hpp"
#include "core/scan/scan_settings.hpp"
#include "process/processes.hpp"
#include "pbnbv/arm_command_t.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/capture_request_t.hpp"
#include "pbnbv/heartbeat_t.hpp"
#include "pbnbv/move_request_t.hpp"
#include "pbnbv/move_result_t.hpp"
#include "pbnbv/point_cloud_t.hpp"
#include "pbnbv/registered_cloud_t.hpp"
#include "pbnbv/voxel_set_t.hpp"
#include "pbnbv/turntable_command_t.hpp"
#include "pbnbv/ellipsoid_set_t.hpp"
#include "pbnbv/plan_request_t.hpp"
#include "pbnbv/view_plan_t.hpp"
#include "service_suite.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace pbnbv;
using namespace pbnbv::testing;

namespace {

// Every service and the twin (a 0.3 m sphere on the arm rig, small images).
class BadInput : public ServiceSuite {
 protected:
  static void SetUpTestSuite() {
    const fs::path dir = fresh_dir("bad-input-mesh");
    write_stl_binary(make_icosphere(0.15, 3), (dir / "sphere.stl").string());
    const std::string bin = bin_dir();
    // A small image keeps rendering fast; the geometry is the same.
    start_suite("bad-input", {
        {"twin", {bin + "/pbnbv-twin", "--rig", "arm", "--mesh", (dir / "sphere.stl").string(), "--object-z", "0.15",
                  "--model-out", (dir / "twin_model.xml").string(), "--width", "320", "--height", "180", "--fx", "174",
                  "--fy", "174", "--speed", "20"}},
        {"motion", {bin + "/pbnbv-motion", "--rig", "arm"}},
        {"camera", {bin + "/pbnbv-camera", "--rig", "arm"}},
        {"registration", {bin + "/pbnbv-registration"}},
        // The map at the registered pose: these tests hand it REGISTERED_CLOUDs.
        {"mapping", {bin + "/pbnbv-mapping", "--out", (dir / "maps").string(), "--map-pose", "registered"}},
        {"ellipsoids", {bin + "/pbnbv-ellipsoids"}},
        {"scorer", {bin + "/pbnbv-scorer", "--rig", "arm"}},
    });
  }
  static void TearDownTestSuite() { stop_suite(); }
};

TEST_F(BadInput, MalformedBytesOnEveryChannelAreRejectedAndCounted) {
  lcm::LCM& lcm = listener_->lcm();
  const std::map<std::string, std::vector<std::string>> subscriptions = {
      {"twin", {"ARM_COMMAND", "TURNTABLE_COMMAND", "DEPTH_TRIGGER"}},
      {"motion", {"MOVE_REQUEST", "ARM_STATUS", "TURNTABLE_STATUS"}},
      {"camera", {"CAPTURE_REQUEST", "DEPTH_FRAME", "ARM_STATUS", "TURNTABLE_STATUS"}},
      {"registration", {"CLOUD"}},
      {"mapping", {"REGISTERED_CLOUD", "DEPTH_FRAME"}},
      {"ellipsoids", {"VOXEL_MAP"}},
      {"scorer", {"PLAN_REQUEST", "VOXEL_MAP", "ELLIPSOIDS"}},
  };
  listener_->spin_until([] { return false; }, 1.2);  // fresh heartbeats
  std::map<std::string, int64_t> before;
  for (const auto& kv : subscriptions) before[kv.first] = rejected(kv.first);
  const std::vector<uint8_t> garbage = {0xde, 0xad, 0xbe, 0xef, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
  std::map<std::string, int> sent;
  for (const auto& kv : subscriptions) {
    for (const auto& channel : kv.second) {
      lcm.publish(channel, garbage.data(), static_cast<unsigned>(garbage.size()));  // wrong type
      lcm.publish(channel, garbage.data(), 0);                                      // empty
    }
  }
  // Right fingerprint, cut in half.
  publish_truncated(lcm, "MOVE_REQUEST", move_request(900, Pose::Identity()));
  publish_truncated(lcm, "CAPTURE_REQUEST", capture_request(900));
  arm_command_t cmd;
  cmd.num_joints = 6;
  cmd.joint_position_rad.assign(6, 0.0);
  cmd.speed_scale = 1;
  cmd.mode = 0;
  publish_truncated(lcm, "ARM_COMMAND", cmd);
  for (const auto& kv : subscriptions) {
    int64_t expected = before[kv.first] + 2 * static_cast<int64_t>(kv.second.size());
    // Status channels are shared: motion and camera both get ARM_STATUS garbage, counted by each.
    EXPECT_TRUE(rejections_reach(kv.first, expected))
        << kv.first << " counted " << rejected(kv.first) << " rejections, expected >= " << expected;
  }
  EXPECT_TRUE(all_running());
  EXPECT_NE(listener_->heartbeats["twin"].last_error.find("arm_command_t.joint_position_rad claims"), std::string::npos)
      << listener_->heartbeats["twin"].last_error;
}

TEST_F(BadInput, OutOfContractValuesAreRejectedWithTheFieldNamed) {
  lcm::LCM& lcm = listener_->lcm();
  // A NaN pose: the motion executor answers kRejected and says which field.
  move_request_t nan_pose = move_request(901, Pose::Identity());
  nan_pose.object_T_camera.position_m[1] = std::nan("");
  lcm.publish("MOVE_REQUEST", &nan_pose);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->moves.count(901) > 0; }, 5.0));
  EXPECT_EQ(listener_->moves[901].status, move_result_t::kRejected);
  EXPECT_NE(listener_->moves[901].reason.find("object_T_camera"), std::string::npos) << listener_->moves[901].reason;

  // An arm command with 5 joints, then one beyond a joint limit: the twin refuses, reports a
  // fault naming the problem in ARM_STATUS, and keeps holding.
  arm_command_t five;
  five.utime = 0;
  five.seq = 777001;
  five.num_joints = 5;
  five.joint_position_rad.assign(5, 0.0);
  five.speed_scale = 1;
  five.mode = arm_command_t::kModePosition;
  lcm.publish("ARM_COMMAND", &five);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->arm.fault.find("777001") != std::string::npos; }, 5.0));
  EXPECT_EQ(listener_->arm.mode, arm_status_t::kModeFault);
  EXPECT_EQ(listener_->arm.fault_code, arm_status_t::kFaultCommandRejected);
  EXPECT_EQ(listener_->arm.fault_command_seq, 777001);
  EXPECT_NE(listener_->arm.fault.find("num_joints"), std::string::npos) << listener_->arm.fault;

  arm_command_t beyond = five;
  beyond.seq = 777002;
  beyond.num_joints = 6;
  beyond.joint_position_rad = listener_->arm.joint_position_rad;
  beyond.joint_position_rad[2] = 10.0;  // a3 far outside its range
  lcm.publish("ARM_COMMAND", &beyond);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->arm.fault.find("777002") != std::string::npos; }, 5.0));
  EXPECT_EQ(listener_->arm.fault_command_seq, 777002);
  EXPECT_EQ(listener_->arm.fault_code, arm_status_t::kFaultOutOfLimits);
  EXPECT_NE(listener_->arm.fault.find("a3"), std::string::npos) << listener_->arm.fault;
  EXPECT_NE(listener_->arm.fault.find("limits"), std::string::npos) << listener_->arm.fault;

  // A capture request with an inverted crop box is rejected by the camera service.
  capture_request_t inverted = capture_request(902);
  inverted.crop_max_m[0] = -1.0;
  const int64_t before = rejected("camera");
  lcm.publish("CAPTURE_REQUEST", &inverted);
  EXPECT_TRUE(rejections_reach("camera", before + 1));
  EXPECT_NE(listener_->heartbeats["camera"].last_error.find("crop_max_m"), std::string::npos)
      << listener_->heartbeats["camera"].last_error;
  EXPECT_TRUE(all_running());
}

TEST_F(BadInput, UnreachableViewIsReportedWithAReason) {
  lcm::LCM& lcm = listener_->lcm();
  // 3 m from the object: beyond the arm's reach from any turntable angle.
  const Pose far = look_at_z_up(Eigen::Vector3d(3.0, 0, 0.5), Eigen::Vector3d::Zero());
  move_request_t r = move_request(903, far);
  lcm.publish("MOVE_REQUEST", &r);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->moves.count(903) > 0; }, 10.0));
  EXPECT_EQ(listener_->moves[903].status, move_result_t::kUnreachable);
  EXPECT_NE(listener_->moves[903].reason.find("reach"), std::string::npos) << listener_->moves[903].reason;
  // Inside the object's keep-out box: unreachable because of a collision.
  const Pose inside = look_at_z_up(Eigen::Vector3d(0.1, 0, 0.05), Eigen::Vector3d::Zero());
  move_request_t r2 = move_request(904, inside);
  lcm.publish("MOVE_REQUEST", &r2);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->moves.count(904) > 0; }, 10.0));
  EXPECT_EQ(listener_->moves[904].status, move_result_t::kUnreachable);
  EXPECT_FALSE(listener_->moves[904].reason.empty());
}

TEST_F(BadInput, ValidRequestsStillSucceedAfterTheGarbage) {
  lcm::LCM& lcm = listener_->lcm();
  const Pose view = look_at_z_up(Eigen::Vector3d(0.75, 0.0, 0.35), Eigen::Vector3d::Zero());
  move_request_t r = move_request(905, view);
  lcm.publish("MOVE_REQUEST", &r);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->moves.count(905) > 0; }, 60.0));
  ASSERT_EQ(listener_->moves[905].status, move_result_t::kReached) << listener_->moves[905].reason;
  // A repeated request id is answered again, not executed twice.
  listener_->moves.erase(905);
  lcm.publish("MOVE_REQUEST", &r);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->moves.count(905) > 0; }, 5.0));
  EXPECT_EQ(listener_->moves[905].status, move_result_t::kReached);

  capture_request_t c = capture_request(906);
  c.not_before_utime = listener_->moves[905].settled_utime;
  lcm.publish("CAPTURE_REQUEST", &c);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->clouds.count(906) > 0; }, 40.0));
  const point_cloud_t& cloud = listener_->clouds[906];
  ASSERT_EQ(cloud.status, point_cloud_t::kOk) << "capture failed: " << cloud.message << "\ncamera log:\n"
                                               << process::tail_lines((dir_ / "camera.log").string(), 20);
  EXPECT_GT(cloud.num_points, 500);
  // Every point lies on the sphere of radius 0.15 m around the object origin (icosphere
  // level 3: the facets sit at most ~1.2 mm inside the sphere).
  int off = 0;
  for (const auto& p : cloud.points_m) {
    const double r_m = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    if (r_m < 0.15 - 0.003 || r_m > 0.15 + 0.001) ++off;
  }
  EXPECT_LT(off, cloud.num_points / 100) << off << " of " << cloud.num_points << " points off the sphere";
  EXPECT_TRUE(all_running());
}

TEST_F(BadInput, CoordinatorFinishesItsScanDespiteGarbageOnItsChannels) {
  // A two-view ring scan of the suite's sphere by a coordinator alone, while every channel it
  // subscribes to also carries malformed messages and answers of another scan.
  ScanSettings s;
  s.scan_id = "garbage-scan";
  s.rig = RigKind::kArm;
  s.rig_model_path = default_rig_path(RigKind::kArm);
  s.planner = PlannerKind::kRing;
  s.views = 2;
  s.object_name = "sphere";
  s.normalisation.extent_m = Eigen::Vector3d::Constant(0.3);
  s.object_z_m = kObjectZ;
  s.keepout_min_m = Eigen::Vector3d(-0.17, -0.17, -0.15);
  s.keepout_max_m = Eigen::Vector3d::Constant(0.17);
  s.sim_speed = 20;
  const fs::path out = dir_ / "coordinator";
  fs::create_directories(out);
  write_json_atomic(to_json(s), (out / "settings.json").string());
  process::Child coordinator;
  coordinator.name = "coordinator";
  coordinator.argv = {bin_dir() + "/pbnbv-coordinator", "--out", out.string()};
  coordinator.log_path = (dir_ / "coordinator.log").string();
  process::start(coordinator);
  std::vector<process::Child> one = {coordinator};

  lcm::LCM& lcm = listener_->lcm();
  const std::vector<uint8_t> garbage = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17};
  move_result_t foreign;  // a well-formed answer for another scan: ignored
  foreign.scan_id = "another-scan";
  foreign.request_id = 0;
  foreign.status = move_result_t::kUnreachable;
  foreign.num_joints = 0;
  int64_t coordinator_rejected = 0;
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (std::chrono::steady_clock::now() < end) {
    process::reap(one);
    if (!one[0].running) break;
    for (const char* channel : {"MOVE_RESULT", "CLOUD", "REGISTERED_CLOUD", "VOXEL_MAP", "ARM_STATUS",
                                "TURNTABLE_STATUS", "HEARTBEAT"}) {
      lcm.publish(channel, garbage.data(), static_cast<unsigned>(garbage.size()));
    }
    lcm.publish("MOVE_RESULT", &foreign);
    listener_->spin_until([] { return false; }, 0.05);
    coordinator_rejected = std::max(coordinator_rejected, rejected("coordinator"));
  }
  process::stop_all(one, 5.0);
  listener_->spin_until([] { return false; }, 0.3);  // its last heartbeat, published on exit
  coordinator_rejected = std::max(coordinator_rejected, rejected("coordinator"));
  EXPECT_EQ(one[0].exit_code, 0) << process::tail_lines(one[0].log_path, 20);
  EXPECT_GT(coordinator_rejected, 0) << "its heartbeat should count the rejected messages";
  const auto scan = read_json((out / "scan.json").string());
  EXPECT_EQ(scan["status"]["state"], "done");
  EXPECT_EQ(scan["status"]["views_done"], 2);
  EXPECT_TRUE(all_running());
}

TEST(LauncherBadInput, MissingMeshFileIsNamed) {
  const CommandResult r = run_command(bin_dir() + "/pbnbv scan --object /nonexistent/thing.obj --no-log --out " +
                                      fresh_dir("missing").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("/nonexistent/thing.obj"), std::string::npos) << r.output;
}

TEST(LauncherBadInput, MalformedMeshIsNamedWithItsLine) {
  const fs::path dir = fresh_dir("malformed");
  {
    std::ofstream obj(dir / "broken.obj");
    obj << "v 0 0 0\nv 1 0 0\nv 0 1 zero\nf 1 2 3\n";
  }
  const CommandResult r = run_command(bin_dir() + "/pbnbv scan --object " + (dir / "broken.obj").string() +
                                      " --no-log --out " + (dir / "out").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("broken.obj"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("line 3"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out" / "logs" / "twin.log")) << "no process may start for a broken mesh";
}

TEST(LauncherBadInput, MistypedOptionIsNamed) {
  const CommandResult r = run_command(bin_dir() + "/pbnbv scan --object sphere --veiws 3 --no-log --out " +
                                      fresh_dir("typo").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--veiws"), std::string::npos) << r.output;
}

}  // namespace


TEST_F(BadInput, BadPlanRequestsAreAnsweredWithTheFieldNamed) {
  lcm::LCM& lcm = listener_->lcm();
  plan_request_t nan_view = plan_request("bad-plan", 2, 0);
  nan_view.num_views_done = 1;
  nan_view.views_done.resize(1);
  nan_view.views_done[0].position_m[0] = std::nan("");
  nan_view.views_done[0].quat_wxyz[0] = 1;
  lcm.publish("PLAN_REQUEST", &nan_view);
  plan_request_t no_candidates = plan_request("bad-plan", 3, 0);
  no_candidates.num_candidates = 0;
  lcm.publish("PLAN_REQUEST", &no_candidates);
  plan_request_t other = plan_request("bad-plan", 4, 0);
  other.planner = 9;  // no planner has this constant
  lcm.publish("PLAN_REQUEST", &other);
  ASSERT_TRUE(listener_->spin_until([] {
    return listener_->plans.count({"bad-plan", 2}) && listener_->plans.count({"bad-plan", 3}) &&
           listener_->plans.count({"bad-plan", 4});
  }, 10.0));
  const view_plan_t& p2 = listener_->plans[std::make_pair(std::string("bad-plan"), int64_t{2})];
  const view_plan_t& p3 = listener_->plans[std::make_pair(std::string("bad-plan"), int64_t{3})];
  const view_plan_t& p4 = listener_->plans[std::make_pair(std::string("bad-plan"), int64_t{4})];
  EXPECT_EQ(p2.outcome, view_plan_t::kFailed);
  EXPECT_NE(p2.reason.find("views_done[0]"), std::string::npos) << p2.reason;
  EXPECT_EQ(p3.outcome, view_plan_t::kFailed);
  EXPECT_NE(p3.reason.find("num_candidates"), std::string::npos) << p3.reason;
  EXPECT_EQ(p4.outcome, view_plan_t::kFailed);
  EXPECT_NE(p4.reason.find("PLAN_REQUEST planner = 9 is not one of its constants (0..4)"), std::string::npos) << p4.reason;
  // A map with NaN voxel centres: the fitter rejects it, names the array and keeps running.
  voxel_set_t bad = synthetic_map("bad-plan", 7);
  bad.frontier_centres_m[0][1] = std::nanf("");
  const int64_t before = rejected("ellipsoids");
  lcm.publish("VOXEL_MAP", &bad);
  EXPECT_TRUE(rejections_reach("ellipsoids", before + 1));
  EXPECT_NE(listener_->heartbeats["ellipsoids"].last_error.find("frontier centre 0"), std::string::npos)
      << listener_->heartbeats["ellipsoids"].last_error;
  EXPECT_TRUE(all_running());
}

// A depth frame the mapping service lost is sent again, and the view is mapped: the mapping
// service does not answer a view whose frame it lacks (the code before answered "not integrated:
// DEPTH_FRAME ... never arrived" after 3 s, and the scan went on without the view in its map);
// the coordinator's repeated capture request makes the camera send the cloud's frame again on
// DEPTH_FRAME_RESENT, and the view is integrated. The frame is "lost" by pushing it out of the
// mapping service's last four frames with four more captures.
TEST_F(BadInput, ALostDepthFrameIsSentAgainAndTheViewIsMapped) {
  lcm::LCM& lcm = listener_->lcm();
  const Pose view = look_at_z_up(Eigen::Vector3d(0.75, 0.0, 0.35), Eigen::Vector3d::Zero());
  move_request_t m = move_request(1905, view);
  lcm.publish("MOVE_REQUEST", &m);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->moves.count(1905) > 0; }, 60.0));
  ASSERT_EQ(listener_->moves[1905].status, move_result_t::kReached) << listener_->moves[1905].reason;
  for (int64_t id = 1950; id <= 1954; ++id) {
    capture_request_t c = capture_request(id);
    c.not_before_utime = listener_->moves[1905].settled_utime;
    lcm.publish("CAPTURE_REQUEST", &c);
    ASSERT_TRUE(listener_->spin_until([id] { return listener_->clouds.count(id) > 0; }, 40.0)) << "capture " << id;
    ASSERT_EQ(listener_->clouds[id].status, point_cloud_t::kOk) << listener_->clouds[id].message;
  }
  const point_cloud_t cloud = listener_->clouds[1950];
  registered_cloud_t r;
  r.utime = 0;
  r.scan_id = "bad-input";
  r.iteration = 40;
  r.request_id = 1950;
  r.cloud = cloud;
  r.kinematic_object_T_camera = cloud.object_T_camera;
  r.accepted = true;
  r.refined = false;
  r.reason = "kinematic pose kept (test)";
  r.constraint = 1;
  r.correction = bus::to_msg(Pose::Identity());
  r.translation_m = r.rotation_deg = r.rmse_m = r.register_s = 0;
  r.overlap = 1;
  r.iterations = 0;
  r.model_points = cloud.num_points;
  r.normals = registered_cloud_t::kNormalsDepthImage;
  r.frame_points = r.model_points_before = 0;
  r.new_points = -1;  // not merged: no figure
  r.new_surface_radius_m = r.accumulate_s = 0;
  lcm.publish("REGISTERED_CLOUD", &r);
  const std::pair<std::string, int32_t> key{"bad-input", 40};
  EXPECT_FALSE(listener_->spin_until([&] { return listener_->maps.count(key) > 0; }, 4.5))
      << "the mapping service answered a view whose frame it lacks: " << listener_->maps[key].message;
  capture_request_t again = capture_request(1950);  // the coordinator's repeat
  lcm.publish("CAPTURE_REQUEST", &again);
  ASSERT_TRUE(listener_->spin_until([&] { return listener_->maps.count(key) > 0; }, 10.0))
      << "mapping log:\n" << process::tail_lines((dir_ / "mapping.log").string(), 10);
  EXPECT_TRUE(listener_->maps[key].updated) << listener_->maps[key].message;
  EXPECT_GT(listener_->maps[key].num_occupied, 0);
  EXPECT_TRUE(all_running());
}
