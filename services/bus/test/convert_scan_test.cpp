// The scan sequence's messages survive the round trip through LCM types, and a bad field is named.
#include "bus/convert_scan.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>

using namespace pbnbv;

namespace {
void expect_error(const std::function<void()>& f, const std::string& needle) {
  try {
    f();
    FAIL() << "expected an error naming " << needle;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}
}  // namespace

TEST(ConvertScan, MoveRequestRoundTripsAndAnEmptyKeepoutStaysEmpty) {
  MoveRequest r;
  r.scan_id = "bunny-1";
  r.iteration = 3;
  r.request_id = 12;
  r.object_T_camera = look_at_z_up(Eigen::Vector3d(0.5, 0.2, 0.4), Eigen::Vector3d::Zero());
  r.object_z_m = 0.15;
  r.keepout = Eigen::AlignedBox3d(Eigen::Vector3d(-0.2, -0.2, -0.15), Eigen::Vector3d(0.2, 0.2, 0.17));
  r.speed_scale = 0.5;
  r.timeout_s = 30;
  const MoveRequest b = bus::from_msg(bus::to_msg(r));
  EXPECT_EQ(b.scan_id, "bunny-1");
  EXPECT_EQ(b.request_id, 12);
  EXPECT_LT((b.object_T_camera.matrix() - r.object_T_camera.matrix()).norm(), 1e-12);
  EXPECT_EQ(b.keepout.min(), r.keepout.min());
  EXPECT_EQ(b.keepout.max(), r.keepout.max());
  r.keepout = Eigen::AlignedBox3d();
  EXPECT_TRUE(bus::from_msg(bus::to_msg(r)).keepout.isEmpty());
}

TEST(ConvertScan, BadRequestFieldsAreNamed) {
  MoveRequest r;
  move_request_t m = bus::to_msg(r);
  m.speed_scale = 0;
  expect_error([&] { bus::from_msg(m); }, "MOVE_REQUEST speed_scale");
  m = bus::to_msg(r);
  m.keepout_min_m[1] = 1.0;  // above its max (0)
  expect_error([&] { bus::from_msg(m); }, "MOVE_REQUEST keepout_max_m[1]");
  CaptureRequest c;
  capture_request_t cm = bus::to_msg(c);
  cm.voxel_m = std::numeric_limits<double>::quiet_NaN();
  expect_error([&] { bus::from_msg(cm); }, "CAPTURE_REQUEST voxel_m");
}

TEST(ConvertScan, CloudRoundTripsItsPointsAndRejectsANonFiniteOne) {
  CaptureResult c;
  c.scan_id = "s";
  c.ok = true;
  c.points = {Eigen::Vector3f(0.1f, 0.2f, 0.3f), Eigen::Vector3f(-1, 0, 2)};
  c.joint_position_rad << 0.1, 0.2, 0.3, 0.4, 0.5, 0.6;
  const CaptureResult b = bus::from_msg(bus::to_msg(c));
  ASSERT_EQ(b.points.size(), 2u);
  EXPECT_EQ(b.points[1], Eigen::Vector3f(-1, 0, 2));
  EXPECT_EQ(b.joint_position_rad, c.joint_position_rad);
  point_cloud_t m = bus::to_msg(c);
  m.points_m[1][2] = std::nanf("");
  expect_error([&] { bus::from_msg(m); }, "CLOUD points_m[1]");
}

TEST(ConvertScan, MoveResultStatusOutsideItsConstantsIsRejected) {
  MoveResult r;
  r.status = MoveStatus::kReached;
  EXPECT_EQ(bus::from_msg(bus::to_msg(r)).status, MoveStatus::kReached);
  move_result_t m = bus::to_msg(r);
  m.status = 9;
  expect_error([&] { bus::from_msg(m); }, "MOVE_RESULT status");
}
