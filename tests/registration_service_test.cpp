// The registration service on a real bus: a view placed 10 cm off by a wrong kinematic pose is
// not moved by a correction its rig's uncertainty does not allow: it is merged where the
// kinematics put it and flagged, saying why, and mapped (a view is never thrown away); a cloud that answers no capture request heard is taken by
// neither service; MESH_REQUESTs are taken only for the model the service holds, the mesh
// already made is not made again, and a flood of different requests makes three meshes at most.
// Runs inside a private network namespace (see CMakeLists.txt).
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <fstream>
#include <cmath>
#include <string>
#include <vector>

#include "bus/convert.hpp"
#include "core/base/format.hpp"
#include "core/geometry/mesh.hpp"
#include "service_suite.hpp"

namespace fs = std::filesystem;
using namespace pbnbv;
using namespace pbnbv::testing;

namespace {

// The registration and mapping services.
class RegistrationService : public ServiceSuite {
 protected:
  static void SetUpTestSuite() {
    const std::string bin = bin_dir();
    start_suite("registration-service", {
        {"registration", {bin + "/pbnbv-registration"}},
        // The map at the registered pose: the view's REGISTERED_CLOUD is what it maps (the rig's
        // pose: mapping_service_test.cpp).
        {"mapping", {bin + "/pbnbv-mapping", "--map-pose", "registered"}},
    });
  }
  static void TearDownTestSuite() { stop_suite(); }

  // The coordinator's CAPTURE_REQUEST for `id` (no camera runs here: only the services that take
  // the capture's answers hear it), and a moment for it to arrive before its answer.
  static void ask_capture(const std::string& scan_id, int64_t id) {
    capture_request_t c = capture_request(id);
    c.scan_id = scan_id;
    listener_->lcm().publish("CAPTURE_REQUEST", &c);
    listener_->spin_until([] { return false; }, 0.2);
  }
};

// A scene of three balls (balls, not boxes: a box shifted along one of its faces still lies on
// that face's plane), as a CLOUD of scan `scan_id`, request and view `id`, shifted by `shift`.
point_cloud_t balls_cloud(const std::string& scan_id, int64_t id, const Eigen::Vector3d& shift) {
  std::vector<Eigen::Vector3d> pts;
  const std::vector<std::pair<double, Eigen::Vector3d>> balls = {
      {0.06, Eigen::Vector3d(0, 0, 0)}, {0.04, Eigen::Vector3d(0.09, 0.03, 0.02)}, {0.03, Eigen::Vector3d(-0.02, 0.08, 0.05)}};
  uint64_t seed = 3;
  for (const auto& [r, c] : balls) {
    for (const auto& p : sample_surface(make_icosphere(r, 3), 8000, seed++)) pts.push_back(p + c);
  }
  point_cloud_t c{};
  c.utime = 0;
  c.scan_id = scan_id;
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
  c.ground_points = 0;
  c.ground_z_m = c.ground_sigma_m = 0;
  std::fill(c.ground_abc, c.ground_abc + 3, 0.0);
  for (const auto& x : pts) {
    const Eigen::Vector3d y = x + shift;
    c.points_m.push_back({static_cast<float>(y.x()), static_cast<float>(y.y()), static_cast<float>(y.z())});
  }
  c.num_points = static_cast<int32_t>(c.points_m.size());
  c.num_normals = 0;  // none: the service fits them to the neighbours
  return c;
}

TEST_F(RegistrationService, AViewTenCentimetresOffKeepsItsKinematicPoseFlagged) {
  // Two views of the balls: the first defines the model; the second is the same surface but placed
  // 10 cm off, as a wildly wrong kinematic pose would place it.
  auto cloud_msg = [](int64_t id, const Eigen::Vector3d& shift) { return balls_cloud("registration-gate", id, shift); };
  lcm::LCM& lcm = listener_->lcm();
  ask_capture("registration-gate", 0);
  const point_cloud_t first = cloud_msg(0, Eigen::Vector3d::Zero());
  lcm.publish("CLOUD", &first);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->registered.count({"registration-gate", 0}) > 0; }, 20.0));
  const registered_cloud_t a = listener_->registered[{"registration-gate", 0}];
  EXPECT_TRUE(a.accepted) << a.reason;
  ask_capture("registration-gate", 1);
  const point_cloud_t off = cloud_msg(1, Eigen::Vector3d(0.1, 0.0, 0.0));
  lcm.publish("CLOUD", &off);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->registered.count({"registration-gate", 1}) > 0; }, 20.0));
  const registered_cloud_t b = listener_->registered[{"registration-gate", 1}];
  EXPECT_TRUE(b.accepted) << b.reason;
  EXPECT_TRUE(b.flagged) << b.reason;
  EXPECT_FALSE(b.refined) << b.reason;
  EXPECT_EQ(b.reason.rfind("kinematic pose kept, flagged (", 0), 0u) << b.reason;
  EXPECT_GT(b.model_points, a.model_points) << "the view is merged";
  // The kinematic pose is kept: the published points are the ones received.
  EXPECT_FLOAT_EQ(b.cloud.points_m[0][0], off.points_m[0][0]);
  // The map answers the view's capture request at once: the view names no depth frame.
  ASSERT_TRUE(listener_->spin_until([] { return listener_->maps.count({"registration-gate", 1}) > 0; }, 20.0));
  const voxel_set_t& m = listener_->maps[{"registration-gate", 1}];
  EXPECT_NE(m.message.find("the view names no depth frame (depth_frame_seq -1)"), std::string::npos) << m.message;
  EXPECT_EQ(m.request_id, 1) << "the map answers the view's capture request";
}

// A CLOUD and a REGISTERED_CLOUD of the scan's id that answer no CAPTURE_REQUEST the services heard
// (forged with a guessed request id): neither is taken, each is refused naming the request; once
// the request is heard, the same REGISTERED_CLOUD is mapped, and the map carries its request id.
// (Before, a well-formed cloud of the current view was integrated whatever its request id, and its
// map cached as the view's answer.)
TEST_F(RegistrationService, CloudsThatAnswerNoCaptureRequestAreNotTaken) {
  lcm::LCM& lcm = listener_->lcm();
  point_cloud_t cloud{};
  cloud.scan_id = "registration-ask";
  cloud.iteration = 3;
  cloud.request_id = 4242;
  cloud.status = point_cloud_t::kOk;
  cloud.frame = "object";
  cloud.object_T_camera = bus::to_msg(look_at_z_up(Eigen::Vector3d(0.8, 0.1, 0.4), Eigen::Vector3d::Zero()));
  cloud.num_joints = 6;
  cloud.joint_position_rad.assign(6, 0.0);
  cloud.depth_frame_seq = -1;
  cloud.voxel_m = 0.002;
  for (int i = 0; i < 200; ++i) cloud.points_m.push_back({0.001f * i, 0.0f, 0.1f});
  cloud.num_points = static_cast<int32_t>(cloud.points_m.size());
  const int64_t registration_before = rejected("registration");
  lcm.publish("CLOUD", &cloud);
  EXPECT_TRUE(rejections_reach("registration", registration_before + 1));
  EXPECT_NE(listener_->heartbeats["registration"].last_error.find(
                "CLOUD of scan 'registration-ask' answers request 4242, which no CAPTURE_REQUEST heard here asked for"),
            std::string::npos)
      << listener_->heartbeats["registration"].last_error;
  EXPECT_EQ(listener_->registered.count({"registration-ask", 3}), 0u);

  registered_cloud_t r{};
  r.scan_id = cloud.scan_id;
  r.iteration = cloud.iteration;
  r.request_id = cloud.request_id;
  r.cloud = cloud;
  r.kinematic_object_T_camera = cloud.object_T_camera;
  r.correction = bus::to_msg(Pose::Identity());
  r.accepted = false;  // no depth frame needed: the map answers without integrating
  r.reason = "rejected (test)";
  const int64_t mapping_before = rejected("mapping");
  lcm.publish("REGISTERED_CLOUD", &r);
  EXPECT_TRUE(rejections_reach("mapping", mapping_before + 1));
  EXPECT_NE(listener_->heartbeats["mapping"].last_error.find("REGISTERED_CLOUD of scan 'registration-ask' answers request 4242"),
            std::string::npos)
      << listener_->heartbeats["mapping"].last_error;
  EXPECT_EQ(listener_->maps.count({"registration-ask", 3}), 0u);

  ask_capture("registration-ask", 4242);
  lcm.publish("REGISTERED_CLOUD", &r);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->maps.count({"registration-ask", 3}) > 0; }, 10.0));
  EXPECT_EQ((listener_->maps[{"registration-ask", 3}].request_id), 4242);
  EXPECT_TRUE(all_running());
}

// The registration service of one scan with its folder, as the launcher starts it.
class MeshRequests : public ServiceSuite {
 protected:
  static constexpr const char* kScan = "registration-mesh";
  static void SetUpTestSuite() {
    out_ = fresh_dir("registration-mesh-out");
    start_suite("registration-mesh", {{"registration", {bin_dir() + "/pbnbv-registration", "--scan", kScan,
                                                        "--out", out_.string()}}});
  }
  static void TearDownTestSuite() { stop_suite(); }
  static mesh_request_t mesh_request(const std::string& scan_id, int64_t id, double spacing_m) {
    mesh_request_t m{};
    m.scan_id = scan_id;
    m.request_id = id;
    m.views = {1};  // view 1: the capture of iteration 0
    m.num_views = 1;
    m.width = 640;
    m.height = 480;
    m.fx = m.fy = 600;
    m.cx = 320;
    m.cy = 240;
    m.point_spacing_m = spacing_m;
    return m;
  }
  // The lines of the service's log that hold `text`.
  static int log_lines(const std::string& text) {
    std::ifstream log(dir_ / "registration.log");
    int n = 0;
    for (std::string line; std::getline(log, line);) n += line.find(text) != std::string::npos;
    return n;
  }
  static bool log_says(const std::string& text) { return log_lines(text) > 0; }
  static int meshes_started() { return log_lines("] meshing "); }
  inline static fs::path out_;
};

// One view merged, then: a MESH_REQUEST of another scan is not taken; the first
// request makes mesh.ply; the same request under a new id is answered with the same mesh without
// making it again; requests that differ (another spacing) make a mesh each until three are made,
// and every one after is answered "no more" at once. The service stays up and answers throughout.
TEST_F(MeshRequests, AFloodOfRequestsMakesThreeMeshesAtMost) {
  lcm::LCM& lcm = listener_->lcm();
  capture_request_t ask = capture_request(0);
  ask.scan_id = kScan;
  lcm.publish("CAPTURE_REQUEST", &ask);
  listener_->spin_until([] { return false; }, 0.2);
  const point_cloud_t view = balls_cloud(kScan, 0, Eigen::Vector3d::Zero());
  lcm.publish("CLOUD", &view);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->registered.count({kScan, 0}) > 0; }, 20.0));
  ASSERT_TRUE((listener_->registered[{kScan, 0}].accepted));
  ASSERT_TRUE(fs::exists(out_ / frame_file_of(0)));

  // A service started for one scan does not take another scan's request (the bus ignores it,
  // saying so); one started for none holds no folder to mesh in.
  const mesh_request_t foreign = mesh_request("another-scan", 1, 0.002);
  lcm.publish("MESH_REQUEST", &foreign);
  listener_->spin_until([] { return listener_->meshes.count({"another-scan", 1}) > 0; }, 2.0);
  EXPECT_EQ(listener_->meshes.count({"another-scan", 1}), 0u);
  EXPECT_TRUE(log_says("ignored a message on MESH_REQUEST of scan 'another-scan' (this process serves scan "
                       "'registration-mesh' only)"));

  auto answer = [&](int64_t id) -> const mesh_result_t* {
    listener_->spin_until([&] { return listener_->meshes.count({kScan, id}) > 0; }, 120.0);
    const auto it = listener_->meshes.find({kScan, id});
    return it == listener_->meshes.end() ? nullptr : &it->second;
  };
  // Each request is sent until it is answered (as the coordinator does): a request that comes
  // while a mesh is made is asked again later.
  auto ask_mesh = [&](const mesh_request_t& m) -> const mesh_result_t* {
    for (int attempt = 0; attempt < 60 && !listener_->meshes.count({m.scan_id, m.request_id}); ++attempt) {
      lcm.publish("MESH_REQUEST", &m);
      listener_->spin_until([&] { return listener_->meshes.count({m.scan_id, m.request_id}) > 0; }, 3.0);
    }
    return answer(m.request_id);
  };
  const mesh_result_t* first = ask_mesh(mesh_request(kScan, 10, 0.002));
  ASSERT_NE(first, nullptr);
  ASSERT_EQ(first->status, mesh_result_t::kOk) << first->message;
  EXPECT_GT(first->triangles, 1000);
  EXPECT_EQ(first->frames, 1);
  EXPECT_TRUE(fs::exists(out_ / "mesh.ply"));
  EXPECT_EQ(meshes_started(), 1);

  const mesh_result_t* again = ask_mesh(mesh_request(kScan, 11, 0.002));
  ASSERT_NE(again, nullptr);
  EXPECT_EQ(again->status, mesh_result_t::kOk);
  EXPECT_EQ(again->triangles, first->triangles);
  EXPECT_EQ(again->seconds, first->seconds) << "the same mesh's figures, not a new mesh's";
  EXPECT_EQ(meshes_started(), 1) << "the same mesh asked under a new id is not made again";

  // Ten different requests: two more meshes (three in all), then "no more".
  int made = 1, refused = 0;
  for (int k = 0; k < 10; ++k) {
    const mesh_result_t* r = ask_mesh(mesh_request(kScan, 20 + k, 0.003 + 0.0005 * k));
    ASSERT_NE(r, nullptr) << "request " << 20 + k << " was not answered";
    if (r->status == mesh_result_t::kOk) {
      ++made;
    } else {
      ++refused;
      EXPECT_NE(r->message.find("3 different meshes of this scan made already"), std::string::npos) << r->message;
    }
  }
  EXPECT_EQ(made, 3);
  EXPECT_EQ(refused, 8);
  EXPECT_EQ(meshes_started(), 3);
  EXPECT_TRUE(all_running());
}

}  // namespace
