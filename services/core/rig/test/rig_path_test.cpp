// Rig time and collision-free paths on models/rig_arm.xml (KUKA KR 10 on its pedestal 1.1 m from
// the turntable axis, along world -y): move times against the speed and acceleration limits by
// hand, a straight joint-space move that sweeps the camera through the object's keep-out box, and
// the detour that replaces it, checked clear all along by an independent, finer sampling.
#include <gtest/gtest.h>

#include <cmath>

#include "core/base/units.hpp"
#include "arm_views.hpp"
#include "core/rig/rig.hpp"

namespace pbnbv {
namespace {

using testing::arm_rig;
using testing::cube_keepout;
using testing::kObjectZ;


TEST(RigTime, ARampIsLimitedBySpeedOrByAccelerationAsWorkedByHand) {
  // Smoothstep: peak speed 1.5 d / T, peak acceleration 6 d / T^2.
  EXPECT_NEAR(ramp_duration_s(1.0, 1.0, 100.0), 1.5, 1e-12);            // speed-limited: 1.5 d / v
  EXPECT_NEAR(ramp_duration_s(1.0, 100.0, 6.0), 1.0, 1e-12);            // acceleration-limited: sqrt(6 d / a)
  EXPECT_EQ(ramp_duration_s(0.0, 1.0, 1.0), 0.0);
}

TEST(RigTime, TheArmsSlowestJointAndTheSlowerOfArmAndTurntableDecide) {
  const RigModel& rig = arm_rig();
  // The rig file: A1 360 deg/s, turntable 60 deg/s; no acceleration limits given, so 4 x speed / s.
  EXPECT_NEAR(rig.qd_max[0], 2 * kPi, 1e-12);
  EXPECT_NEAR(rig.qdd_max[0], 8 * kPi, 1e-12);
  EXPECT_NEAR(rig.turntable_qdd_max, 4 * kPi / 3, 1e-12);
  Vector6d a = rig.q_home, b = rig.q_home;
  b[0] += 1.0;  // A1 one radian: max(1.5 / 2 pi, sqrt(6 / 8 pi)) = max(0.239, 0.489) s
  EXPECT_NEAR(arm_move_s(rig, a, b), std::sqrt(6.0 / (8 * kPi)), 1e-12);
  b[1] += 1.0;  // A2 (300 deg/s) one radian too: sqrt(6 / (4 x 5 pi / 3)) = 0.535 s, the slower
  EXPECT_NEAR(arm_move_s(rig, a, b), std::sqrt(6.0 / (4 * 5 * kPi / 3)), 1e-12);
  // Half a turn of the turntable: max(1.5 pi / (pi / 3), sqrt(6 pi / (4 pi / 3))) = max(4.5, 2.12) s.
  EXPECT_NEAR(turntable_move_s(rig, 0, kPi), 4.5, 1e-12);
  EXPECT_NEAR(move_s(rig, {a, 0}, {b, kPi}), 4.5, 1e-12);
  EXPECT_NEAR(move_s(rig, {a, 0}, {b, 0.01}), std::sqrt(6.0 / (4 * 5 * kPi / 3)), 1e-12);
  // At half speed the speed and acceleration limits both halve: the speed-limited turntable 9 s.
  EXPECT_NEAR(turntable_move_s(rig, 0, kPi, 0.5), 9.0, 1e-12);
  // A path: through two stops, the sum of its moves.
  EXPECT_NEAR(path_s(rig, {a, 0}, {{a, kPi}, {b, kPi}}), 4.5 + std::sqrt(6.0 / (4 * 5 * kPi / 3)), 1e-12);
}

// Every state on the straight move a -> b, 1 mm of the camera's travel apart at most (a finer
// and independent check of path_collision's sampling), collides with nothing.
void expect_clear_all_along(ReachabilityChecker& checker, const RigModel& rig, const RigState& a, const RigState& b,
                            const Eigen::AlignedBox3d& keepout, const std::string& leg) {
  const double travel = (camera_in_world(rig, a.q).translation() - camera_in_world(rig, b.q).translation()).norm();
  const int n = std::max(50, static_cast<int>(std::ceil(travel / 0.001)) * 4);
  for (int k = 0; k <= n; ++k) {
    const double s = static_cast<double>(k) / n;
    const double t = a.turntable_rad + s * (b.turntable_rad - a.turntable_rad);
    const std::vector<std::string> c = checker.collisions(a.q + s * (b.q - a.q), t, keepout, kObjectZ);
    ASSERT_TRUE(c.empty()) << leg << " at " << s << ": " << c.front();
  }
}

TEST(RigPath, AMoveAroundTheObjectOnTheArmsBaseArcCrossesTheKeepOutBoxAndADetourDoesNot) {
  const RigModel& rig = arm_rig();
  ReachabilityChecker checker(rig);
  // A tall object (keep-out box 0.3 x 0.3 x 0.5 m). Its two front corners seen from 0.55 m at 50 deg
  // either side of the arm's base (world -y), 0.2 m up: turning A1 carries the camera on a circle
  // about the base, 1.1 m away, whose middle passes 0.14 m in front of the object's centre: through
  // the box.
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-0.15, -0.15, -0.15), Eigen::Vector3d(0.15, 0.15, 0.35));
  const double side = 0.55 * std::sin(50 * kPi / 180), front = -0.55 * std::cos(50 * kPi / 180);
  const RigState left{testing::config_seeing_from(rig, Eigen::Vector3d(-side, front, 0.2), kObjectZ), 0};
  const RigState right{testing::config_seeing_from(rig, Eigen::Vector3d(side, front, 0.2), kObjectZ), 0};
  ASSERT_TRUE(checker.collisions(left.q, 0, box, kObjectZ).empty());
  ASSERT_TRUE(checker.collisions(right.q, 0, box, kObjectZ).empty());
  // Midway in joint space the camera is inside the box.
  const Vector6d mid = 0.5 * (left.q + right.q);
  const Eigen::Vector3d cam_mid = (object_in_world(rig, 0, kObjectZ).inverse() * camera_in_world(rig, mid)).translation();
  EXPECT_TRUE(box.contains(cam_mid)) << "camera midway at " << cam_mid.transpose();

  const std::string hit = checker.path_collision(left, right, box, kObjectZ);
  EXPECT_NE(hit.find("keepout"), std::string::npos) << hit;
  const RigPath path = checker.plan_path(left, right, box, kObjectZ);
  ASSERT_TRUE(path.clear) << path.reason;
  EXPECT_NE(path.route, "direct");
  ASSERT_FALSE(path.stops.empty());
  EXPECT_EQ(path.stops.back().q, right.q);
  EXPECT_NEAR(path.time_s, path_s(rig, left, path.stops), 1e-12);
  EXPECT_GT(path.time_s, move_s(rig, left, right));  // a detour costs time
  RigState at = left;
  for (std::size_t i = 0; i < path.stops.size(); ++i) {
    expect_clear_all_along(checker, rig, at, path.stops[i], box, path.route + ", leg " + std::to_string(i + 1));
    at = path.stops[i];
  }
}

TEST(RigPath, ThePathsSamplingCatchesAPlateThinnerThanItsStep) {
  const RigModel& rig = arm_rig();
  ReachabilityChecker checker(rig);
  // The camera lowered on the object's side facing the arm, from 0.4 m to 0 m up; a keep-out plate
  // 1 mm thick (a quarter of the sampling step), 6 x 6 cm, where the camera is halfway.
  const RigState high{testing::config_seeing_from(rig, Eigen::Vector3d(0, -0.6, 0.4), kObjectZ), 0};
  const RigState low{testing::config_seeing_from(rig, Eigen::Vector3d(0, -0.6, 0.0), kObjectZ), 0};
  const Eigen::Vector3d halfway =
      (object_in_world(rig, 0, kObjectZ).inverse() * camera_in_world(rig, 0.5 * (high.q + low.q))).translation();
  const Eigen::AlignedBox3d plate(halfway - Eigen::Vector3d(0.03, 0.03, 0.0005), halfway + Eigen::Vector3d(0.03, 0.03, 0.0005));
  ASSERT_TRUE(checker.collisions(high.q, 0, plate, kObjectZ).empty());
  ASSERT_TRUE(checker.collisions(low.q, 0, plate, kObjectZ).empty());
  EXPECT_NE(checker.path_collision(high, low, plate, kObjectZ).find("keepout"), std::string::npos);
  // Without the plate the same move is clear.
  EXPECT_EQ(checker.path_collision(high, low, Eigen::AlignedBox3d(), kObjectZ), "");
}

TEST(RigPath, ATurningTurntableSweepsTheKeepOutBoxWhateverTheTiming) {
  const RigModel& rig = arm_rig();
  ReachabilityChecker checker(rig);
  // A long narrow box (0.57 x 0.1 m, long along the object's x) and the camera 0.28 m from the
  // axis on the object's -y side, looking at it: clear at 0 and at 180 deg, where the box lies
  // across the camera's view; at 90 deg its end reaches 0.285 m out towards the camera: only
  // the sweep (a cylinder of radius hypot(0.285, 0.05) = 0.289 m) collides.
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-0.285, -0.05, -0.1), Eigen::Vector3d(0.285, 0.05, 0.1));
  const RigState near_side{testing::config_seeing_from(rig, Eigen::Vector3d(0, -0.28, 0.0), kObjectZ), 0};
  ASSERT_TRUE(checker.collisions(near_side.q, 0, box, kObjectZ).empty());
  ASSERT_TRUE(checker.collisions(near_side.q, kPi, box, kObjectZ).empty());
  EXPECT_FALSE(checker.collisions(near_side.q, kPi / 2, box, kObjectZ).empty());
  EXPECT_EQ(checker.path_collision(near_side, {near_side.q, 0}, box, kObjectZ), "");
  EXPECT_NE(checker.path_collision(near_side, {near_side.q, kPi}, box, kObjectZ).find("keepout"), std::string::npos);
}

}  // namespace
}  // namespace pbnbv
