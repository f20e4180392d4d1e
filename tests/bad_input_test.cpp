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

#include "core/mesh.hpp"
#include "core/geometry.hpp"
#include "core/scan_settings.hpp"
#include "launcher/processes.hpp"
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
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace pbnbv;
using namespace pbnbv::testing;

namespace {

constexpr double kObjectZ = 0.15;  // a 0.3 m sphere resting on the turntable

class Listener {
 public:
  Listener() : lcm_("udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608") {
    lcm_.subscribe("HEARTBEAT", &Listener::on_heartbeat, this);
    lcm_.subscribe("MOVE_RESULT", &Listener::on_move, this);
    lcm_.subscribe("CLOUD", &Listener::on_cloud, this);
    lcm_.subscribe("ARM_STATUS", &Listener::on_arm, this);
    lcm_.subscribe("REGISTERED_CLOUD", &Listener::on_registered, this);
    lcm_.subscribe("VOXEL_MAP", &Listener::on_map, this);
  }
  lcm::LCM& lcm() { return lcm_; }
  // Handles messages until `done` or the timeout; returns done().
  bool spin_until(const std::function<bool()>& done, double timeout_s) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < end) {
      if (done()) return true;
      lcm_.handleTimeout(20);
    }
    return done();
  }
  std::map<std::string, heartbeat_t> heartbeats;
  std::map<int64_t, move_result_t> moves;
  std::map<int64_t, point_cloud_t> clouds;
  arm_status_t arm;
  bool have_arm = false;
  std::map<std::pair<std::string, int64_t>, registered_cloud_t> registered;
  std::map<std::pair<std::string, int32_t>, voxel_set_t> maps;

 private:
  void on_heartbeat(const lcm::ReceiveBuffer*, const std::string&, const heartbeat_t* m) { heartbeats[m->service] = *m; }
  void on_move(const lcm::ReceiveBuffer*, const std::string&, const move_result_t* m) { moves[m->request_id] = *m; }
  void on_cloud(const lcm::ReceiveBuffer*, const std::string&, const point_cloud_t* m) { clouds[m->request_id] = *m; }
  void on_arm(const lcm::ReceiveBuffer*, const std::string&, const arm_status_t* m) { arm = *m; have_arm = true; }
  void on_registered(const lcm::ReceiveBuffer*, const std::string&, const registered_cloud_t* m) {
    registered[{m->scan_id, m->request_id}] = *m;
  }
  void on_map(const lcm::ReceiveBuffer*, const std::string&, const voxel_set_t* m) { maps[{m->scan_id, m->iteration}] = *m; }
  lcm::LCM lcm_;
};

move_request_t move_request(int64_t id, const Pose& object_T_camera) {
  move_request_t r;
  r.utime = 0;
  r.scan_id = "bad-input";
  r.iteration = 0;
  r.request_id = id;
  double p[3], q[4];
  pose_to_arrays(object_T_camera, p, q);
  std::copy(p, p + 3, r.object_T_camera.position_m);
  std::copy(q, q + 4, r.object_T_camera.quat_wxyz);
  r.object_z_m = kObjectZ;
  for (int k = 0; k < 3; ++k) {
    r.keepout_min_m[k] = -0.17;
    r.keepout_max_m[k] = 0.17;
  }
  r.keepout_min_m[2] = -0.15;
  r.speed_scale = 1.0;
  r.timeout_s = 60;
  r.plan_only = false;
  return r;
}

capture_request_t capture_request(int64_t id) {
  capture_request_t r;
  r.utime = 0;
  r.scan_id = "bad-input";
  r.iteration = 0;
  r.request_id = id;
  r.not_before_utime = 0;
  r.object_z_m = kObjectZ;
  for (int k = 0; k < 3; ++k) {
    r.crop_min_m[k] = -0.3;
    r.crop_max_m[k] = 0.3;
  }
  r.ground_clearance_m = 0.004;
  r.voxel_m = 0.002;
  r.timeout_s = 10;
  return r;
}

template <class T>
void publish_truncated(lcm::LCM& lcm, const std::string& channel, const T& msg) {
  std::vector<uint8_t> buf(msg.getEncodedSize());
  msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
  lcm.publish(channel, buf.data(), static_cast<unsigned>(buf.size() / 2));
}

class BadInput : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fresh_dir("bad-input");
    TriangleMesh sphere = make_icosphere(0.15, 3);
    write_stl_binary(sphere, (dir_ / "sphere.stl").string());
    const std::string bin = bin_dir();
    auto add = [&](const std::string& name, std::vector<std::string> argv) {
      launcher::Child c;
      c.name = name;
      c.argv = std::move(argv);
      c.log_path = (dir_ / (name + ".log")).string();
      children_.push_back(c);
    };
    // A small image keeps rendering fast; the geometry is the same.
    add("twin", {bin + "/pbnbv-twin", "--rig", "arm", "--mesh", (dir_ / "sphere.stl").string(),
                 "--object-z", "0.15", "--model-out", (dir_ / "twin_model.xml").string(),
                 "--width", "320", "--height", "180", "--fx", "174", "--fy", "174", "--speed", "20"});
    add("motion", {bin + "/pbnbv-motion", "--rig", "arm"});
    add("camera", {bin + "/pbnbv-camera", "--rig", "arm"});
    add("registration", {bin + "/pbnbv-registration"});
    add("mapping", {bin + "/pbnbv-mapping", "--out", (dir_ / "maps").string()});
    for (auto& c : children_) launcher::start(c);
    listener_ = new Listener();
    ASSERT_TRUE(listener_->spin_until([] {
      return listener_->heartbeats.count("twin") && listener_->heartbeats.count("motion") &&
             listener_->heartbeats.count("camera") && listener_->heartbeats.count("registration") &&
             listener_->heartbeats.count("mapping") && listener_->have_arm;
    }, 60)) << "services did not start; twin log:\n" << launcher::tail_lines((dir_ / "twin.log").string(), 20);
  }

  static void TearDownTestSuite() {
    launcher::stop_all(children_, 5.0);
    for (const auto& c : children_) {
      EXPECT_EQ(c.exit_code, 0) << c.name << " did not exit cleanly:\n" << launcher::tail_lines(c.log_path, 20);
    }
    delete listener_;
  }

  static bool all_running() {
    launcher::reap(children_);
    for (const auto& c : children_) if (!c.running) return false;
    return true;
  }

  static int64_t rejected(const std::string& service) {
    auto it = listener_->heartbeats.find(service);
    return it == listener_->heartbeats.end() ? -1 : it->second.messages_rejected;
  }

  // Waits for fresh heartbeats (published at 1 Hz) that count at least `n` more rejections.
  static bool rejections_reach(const std::string& service, int64_t n) {
    return listener_->spin_until([&] { return rejected(service) >= n; }, 5.0);
  }

  static fs::path dir_;
  static std::vector<launcher::Child> children_;
  static Listener* listener_;
};
fs::path BadInput::dir_;
std::vector<launcher::Child> BadInput::children_;
Listener* BadInput::listener_ = nullptr;

TEST_F(BadInput, MalformedBytesOnEveryChannelAreRejectedAndCounted) {
  lcm::LCM& lcm = listener_->lcm();
  const std::map<std::string, std::vector<std::string>> subscriptions = {
      {"twin", {"ARM_COMMAND", "TURNTABLE_COMMAND", "DEPTH_TRIGGER"}},
      {"motion", {"MOVE_REQUEST", "ARM_STATUS", "TURNTABLE_STATUS"}},
      {"camera", {"CAPTURE_REQUEST", "DEPTH_FRAME", "ARM_STATUS", "TURNTABLE_STATUS"}},
      {"registration", {"CLOUD"}},
      {"mapping", {"REGISTERED_CLOUD", "DEPTH_FRAME"}},
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
  EXPECT_NE(listener_->heartbeats["twin"].last_error.find("does not decode"), std::string::npos)
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
  EXPECT_NE(listener_->arm.fault.find("num_joints"), std::string::npos) << listener_->arm.fault;

  arm_command_t beyond = five;
  beyond.seq = 777002;
  beyond.num_joints = 6;
  beyond.joint_position_rad = listener_->arm.joint_position_rad;
  beyond.joint_position_rad[2] = 10.0;  // a3 far outside its range
  lcm.publish("ARM_COMMAND", &beyond);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->arm.fault.find("777002") != std::string::npos; }, 5.0));
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
                                               << launcher::tail_lines((dir_ / "camera.log").string(), 20);
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
  s.planner = "ring";
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
  launcher::Child coordinator;
  coordinator.name = "coordinator";
  coordinator.argv = {bin_dir() + "/pbnbv-coordinator", "--out", out.string()};
  coordinator.log_path = (dir_ / "coordinator.log").string();
  launcher::start(coordinator);
  std::vector<launcher::Child> one = {coordinator};

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
    launcher::reap(one);
    if (!one[0].running) break;
    for (const char* channel : {"MOVE_RESULT", "CLOUD", "REGISTERED_CLOUD", "VOXEL_MAP", "ARM_STATUS",
                                "TURNTABLE_STATUS", "HEARTBEAT"}) {
      lcm.publish(channel, garbage.data(), static_cast<unsigned>(garbage.size()));
    }
    lcm.publish("MOVE_RESULT", &foreign);
    listener_->spin_until([] { return false; }, 0.05);
    coordinator_rejected = std::max(coordinator_rejected, rejected("coordinator"));
  }
  launcher::stop_all(one, 5.0);
  listener_->spin_until([] { return false; }, 0.3);  // its last heartbeat, published on exit
  coordinator_rejected = std::max(coordinator_rejected, rejected("coordinator"));
  EXPECT_EQ(one[0].exit_code, 0) << launcher::tail_lines(one[0].log_path, 20);
  EXPECT_GT(coordinator_rejected, 0) << "its heartbeat should count the rejected messages";
  const auto scan = read_json((out / "scan.json").string());
  EXPECT_EQ(scan["status"]["state"], "done");
  EXPECT_EQ(scan["status"]["views_done"], 2);
  EXPECT_TRUE(all_running());
}

TEST_F(BadInput, AViewTenCentimetresOffIsRejectedAndNotMerged) {
  // Two views of a scene of three balls: the first defines the model; the second is the same
  // surface but placed 10 cm off, as a wildly wrong kinematic pose would place it. (Balls, not
  // boxes: a box shifted along one of its faces still lies on that face's plane.)
  std::vector<Eigen::Vector3d> pts;
  const std::vector<std::pair<double, Eigen::Vector3d>> balls = {
      {0.06, Eigen::Vector3d(0, 0, 0)}, {0.04, Eigen::Vector3d(0.09, 0.03, 0.02)}, {0.03, Eigen::Vector3d(-0.02, 0.08, 0.05)}};
  uint64_t seed = 3;
  for (const auto& [r, c] : balls) {
    for (const auto& p : sample_surface(make_icosphere(r, 3), 8000, seed++)) pts.push_back(p + c);
  }
  auto cloud_msg = [&](int64_t id, const Eigen::Vector3d& shift) {
    point_cloud_t c;
    c.utime = 0;
    c.scan_id = "registration-gate";
    c.iteration = static_cast<int32_t>(id);
    c.request_id = id;
    c.status = point_cloud_t::kOk;
    c.frame = "object";
    double p[3], q[4];
    pose_to_arrays(look_at_z_up(Eigen::Vector3d(0.8, 0.1, 0.4), Eigen::Vector3d::Zero()), p, q);
    std::copy(p, p + 3, c.object_T_camera.position_m);
    std::copy(q, q + 4, c.object_T_camera.quat_wxyz);
    c.num_joints = 6;
    c.joint_position_rad.assign(6, 0.0);
    c.turntable_angle_rad = 0;
    c.depth_frame_seq = -1;  // no depth frame: the map cannot integrate it either way
    c.depth_frame_utime = 0;
    c.num_valid_pixels = c.num_cropped = 0;
    c.voxel_m = 0.002;
    c.capture_s = c.process_s = 0;
    for (const auto& x : pts) {
      const Eigen::Vector3d y = x + shift;
      c.points_m.push_back({static_cast<float>(y.x()), static_cast<float>(y.y()), static_cast<float>(y.z())});
    }
    c.num_points = static_cast<int32_t>(c.points_m.size());
    return c;
  };
  lcm::LCM& lcm = listener_->lcm();
  const point_cloud_t first = cloud_msg(0, Eigen::Vector3d::Zero());
  lcm.publish("CLOUD", &first);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->registered.count({"registration-gate", 0}) > 0; }, 20.0));
  const registered_cloud_t a = listener_->registered[{"registration-gate", 0}];
  EXPECT_TRUE(a.accepted) << a.reason;
  const point_cloud_t off = cloud_msg(1, Eigen::Vector3d(0.1, 0.0, 0.0));
  lcm.publish("CLOUD", &off);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->registered.count({"registration-gate", 1}) > 0; }, 20.0));
  const registered_cloud_t b = listener_->registered[{"registration-gate", 1}];
  EXPECT_FALSE(b.accepted) << b.reason;
  EXPECT_NE(b.reason.find("rejected"), std::string::npos) << b.reason;
  EXPECT_EQ(b.model_points, a.model_points) << "a rejected view must not be merged into the model";
  // The kinematic pose is kept: the published points are the ones received.
  EXPECT_FLOAT_EQ(b.cloud.points_m[0][0], off.points_m[0][0]);
  // And the map does not integrate it, saying why.
  ASSERT_TRUE(listener_->spin_until([] { return listener_->maps.count({"registration-gate", 1}) > 0; }, 20.0));
  const voxel_set_t& m = listener_->maps[{"registration-gate", 1}];
  EXPECT_FALSE(m.updated);
  EXPECT_NE(m.message.find("registration rejected"), std::string::npos) << m.message;
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
