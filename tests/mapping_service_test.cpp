// The mapping service with the map at the rig's pose (--map-pose rig) on a real bus: a view is
// integrated from its CLOUD at the camera's kinematic pose, moved by the camera-frame correction
// the registration found for the view before (kinematic^-1 * registered), so the map answers
// without waiting for the view's own registration. Checked by hand on a wall seen head-on: the
// correction moves the camera 6 cm along its axis, and the wall's voxels move two voxels with it.
// Runs inside a private network namespace (see CMakeLists.txt).
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "bus/convert.hpp"
#include "pbnbv/depth_frame_t.hpp"
#include "service_suite.hpp"

using namespace pbnbv;
using namespace pbnbv::testing;

namespace {

constexpr double kResolution = 0.03;
const char* const kScan = "rig-pose";

class MappingAtTheRigsPose : public ServiceSuite {
 protected:
  static void SetUpTestSuite() {
    start_suite("mapping-rig-pose",
                {{"mapping", {bin_dir() + "/pbnbv-mapping", "--map-pose", "rig", "--resolution", "0.03"}}});
  }
  static void TearDownTestSuite() { stop_suite(); }

  static void ask_capture(int64_t id, int iteration) {
    capture_request_t c = capture_request(id);
    c.scan_id = kScan;
    c.iteration = iteration;
    listener_->lcm().publish("CAPTURE_REQUEST", &c);
    listener_->spin_until([] { return false; }, 0.2);
  }
};

// A 64 x 48 depth image of a wall `depth_m` in front of the camera, every pixel (raw counts of 0.1 mm).
depth_frame_t wall_frame(int64_t seq, double depth_m) {
  depth_frame_t f{};
  f.camera_id = "test";
  f.seq = seq;
  f.trigger_seq = -1;
  f.scan_id = kScan;
  f.width = 64;
  f.height = 48;
  f.fx = f.fy = 50;
  f.cx = 31.5;
  f.cy = 23.5;
  f.depth_min_m = 0.1;
  f.depth_max_m = 2.0;
  f.depth_unit_m = 1e-4;
  f.encoding = depth_frame_t::kEncodingRaw;
  const auto counts = static_cast<uint16_t>(std::lround(depth_m / f.depth_unit_m));
  f.depth.resize(static_cast<std::size_t>(f.width) * f.height * 2);
  for (std::size_t i = 0; i < f.depth.size(); i += 2) {
    f.depth[i] = static_cast<uint8_t>(counts & 0xff);
    f.depth[i + 1] = static_cast<uint8_t>(counts >> 8);
  }
  f.num_bytes = static_cast<int32_t>(f.depth.size());
  f.depth_T_colour = bus::to_msg(Pose::Identity());
  f.colour_encoding = depth_frame_t::kColourNone;
  return f;
}

// The camera's CLOUD of view `iteration` (request `id`), taken at `kinematic` from frame `seq`.
point_cloud_t cloud_at(int64_t id, int iteration, const Pose& kinematic, int64_t seq) {
  point_cloud_t c{};
  c.scan_id = kScan;
  c.iteration = iteration;
  c.request_id = id;
  c.status = point_cloud_t::kOk;
  c.frame = "object";
  c.object_T_camera = bus::to_msg(kinematic);
  c.num_joints = 6;
  c.joint_position_rad.assign(6, 0.0);
  c.depth_frame_seq = seq;
  c.voxel_m = 0.002;
  for (int i = 0; i < 10; ++i) c.points_m.push_back({0.01f, 0.01f * i, 0.0f});  // a few: counted, not mapped
  c.num_points = static_cast<int32_t>(c.points_m.size());
  return c;
}

// The largest x of the map's occupied voxel centres.
double max_occupied_x(const voxel_set_t& m) {
  double x = -1e9;
  for (const auto& c : m.occupied_centres_m) x = std::max(x, static_cast<double>(c[0]));
  return x;
}

TEST_F(MappingAtTheRigsPose, AViewIsMappedAtTheRigsPoseMovedByTheLastRegistrationsCorrection) {
  lcm::LCM& lcm = listener_->lcm();
  // The camera 0.61 m from the object's origin on -x, looking along +x: the wall at depth 0.61 m is
  // the plane x = 0 ... + 0.01 m, inside one voxel whichever way the grid falls (boundaries at
  // multiples of 3 cm or half-way between: 0.01 m is at least 5 mm from both).
  const Pose kinematic = look_at_z_up(Eigen::Vector3d(-0.60, 0, 0), Eigen::Vector3d(1, 0, 0));
  ask_capture(1, 0);
  depth_frame_t f0 = wall_frame(7, 0.61);
  lcm.publish("DEPTH_FRAME", &f0);
  point_cloud_t c0 = cloud_at(1, 0, kinematic, 7);
  lcm.publish("CLOUD", &c0);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->maps.count({kScan, 0}) > 0; }, 20.0));
  const voxel_set_t m0 = listener_->maps[{kScan, 0}];
  ASSERT_TRUE(m0.updated) << m0.message;
  ASSERT_GT(m0.num_occupied, 0);
  const double wall0 = max_occupied_x(m0);
  EXPECT_LT(std::abs(wall0 - 0.01), kResolution / 2 + 1e-6) << "the voxel holding x = 0.01 m";
  for (const auto& c : m0.occupied_centres_m) EXPECT_NEAR(c[0], wall0, 1e-6) << "one layer of voxels";

  // The registration answers view 0: the camera was 6 cm further along its optical axis than the
  // kinematics said (a correction in the camera's frame).
  Pose shift = Pose::Identity();
  shift.translation() = Eigen::Vector3d(0, 0, 0.06);
  registered_cloud_t r{};
  r.scan_id = kScan;
  r.iteration = 0;
  r.request_id = 1;
  r.accepted = true;
  r.refined = true;
  r.cloud = c0;
  r.cloud.object_T_camera = bus::to_msg(Pose(kinematic * shift));
  r.cloud.num_points = 0;
  r.cloud.points_m.clear();
  r.kinematic_object_T_camera = bus::to_msg(kinematic);
  r.correction = bus::to_msg(Pose::Identity());
  lcm.publish("REGISTERED_CLOUD", &r);
  listener_->spin_until([] { return false; }, 0.3);

  // View 1 from the same kinematic pose and the same image: mapped 6 cm (two voxels) further on,
  // before any registration of view 1.
  ask_capture(2, 1);
  depth_frame_t f1 = wall_frame(8, 0.61);
  lcm.publish("DEPTH_FRAME", &f1);
  point_cloud_t c1 = cloud_at(2, 1, kinematic, 8);
  lcm.publish("CLOUD", &c1);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->maps.count({kScan, 1}) > 0; }, 20.0));
  const voxel_set_t m1 = listener_->maps[{kScan, 1}];
  ASSERT_TRUE(m1.updated) << m1.message;
  EXPECT_NEAR(max_occupied_x(m1), wall0 + 2 * kResolution, 1e-6);
  EXPECT_EQ(m1.request_id, 2) << "the map answers the view's capture request";

  // A view without a point is not integrated, and says so.
  ask_capture(3, 2);
  point_cloud_t empty = cloud_at(3, 2, kinematic, 9);
  empty.points_m.clear();
  empty.num_points = 0;
  lcm.publish("CLOUD", &empty);
  ASSERT_TRUE(listener_->spin_until([] { return listener_->maps.count({kScan, 2}) > 0; }, 20.0));
  const voxel_set_t& m2 = listener_->maps[{kScan, 2}];
  EXPECT_FALSE(m2.updated);
  EXPECT_EQ(m2.message, "not integrated: the view has no point");
}

}  // namespace
