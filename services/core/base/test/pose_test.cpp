// Poses, look-at and angle helpers.
#include <gtest/gtest.h>

#include <cmath>

#include "core/base/pose.hpp"
#include "core/base/units.hpp"

using namespace pbnbv;

TEST(Pose, LookAtPointsTheOpticalAxisAtTheTargetWithImageUpAlongUp) {
  const Pose p = look_at(Eigen::Vector3d(1, 0, 0), Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());
  EXPECT_TRUE(p.linear().col(2).isApprox(Eigen::Vector3d(-1, 0, 0)));   // z: forward
  EXPECT_TRUE(p.linear().col(1).isApprox(Eigen::Vector3d(0, 0, -1)));   // y: down
  EXPECT_TRUE(p.linear().col(0).isApprox(Eigen::Vector3d(0, 1, 0)));    // x: right (forward x up)
  EXPECT_NEAR(p.linear().determinant(), 1.0, 1e-12);
  EXPECT_THROW(look_at(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ()), std::invalid_argument);
  EXPECT_THROW(look_at(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ()), std::invalid_argument);
  // Straight down works with the z-up helper.
  const Pose down = look_at_z_up(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d::Zero());
  EXPECT_TRUE(down.linear().col(2).isApprox(Eigen::Vector3d(0, 0, -1)));
}

TEST(Pose, PoseArraysRoundTripAndRejectBadQuaternions) {
  const Pose p = look_at(Eigen::Vector3d(0.3, -0.2, 0.5), Eigen::Vector3d(0, 0.1, 0), Eigen::Vector3d::UnitZ());
  double pos[3], quat[4];
  pose_to_arrays(p, pos, quat);
  EXPECT_GE(quat[0], 0.0);
  const Pose back = pose_from_arrays(pos, quat, "test");
  EXPECT_TRUE(back.isApprox(p, 1e-12));
  double bad[4] = {1, 1, 0, 0};
  try {
    pose_from_arrays(pos, bad, "MOVE_REQUEST object_T_camera");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("MOVE_REQUEST object_T_camera"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("norm"), std::string::npos);
  }
  double nan_pos[3] = {0, std::nan(""), 0};
  EXPECT_THROW(pose_from_arrays(nan_pos, quat, "x"), std::invalid_argument);
}

TEST(Pose, AnglesWrapAndFindTheNearestEquivalent) {
  EXPECT_NEAR(wrap_angle_rad(3 * kPi / 2), -kPi / 2, 1e-12);
  EXPECT_NEAR(wrap_angle_rad(-kPi), kPi, 1e-12);
  EXPECT_NEAR(nearest_equivalent_angle_rad(0.1, 6.2), 0.1 + 2 * kPi, 1e-12);
  EXPECT_NEAR(nearest_equivalent_angle_rad(-kPi / 2, -3.0), -kPi / 2, 1e-12);
  EXPECT_NEAR(rotation_angle_rad(Eigen::Matrix3d::Identity(),
                                 Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()).toRotationMatrix()), 0.3, 1e-12);
}

TEST(Pose, RotationAngleIsAccurateFromZeroToPi) {
  const Eigen::Vector3d axis = Eigen::Vector3d(1, -2, 0.5).normalized();
  const Eigen::Matrix3d a = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, 0.1, -1).normalized()).toRotationMatrix();
  // Tiny angles: acos((trace - 1) / 2) reads 1e-9 rad as 0 (or 2e-8); the relative error here
  // stays at the level of the matrices' rounding.
  for (double angle : {1e-12, 1e-9, 1e-6, 1e-3, 0.5, 2.0, kPi - 1e-3}) {
    const Eigen::Matrix3d b = a * Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    EXPECT_NEAR(rotation_angle_rad(a, b), angle, 1e-15 + 1e-9 * angle) << angle;
    EXPECT_NEAR(rotation_angle_rad(b, a), angle, 1e-15 + 1e-9 * angle) << angle;
  }
  EXPECT_NEAR(rotation_angle_rad(a, a * Eigen::AngleAxisd(kPi, axis).toRotationMatrix()), kPi, 1e-7);
  EXPECT_EQ(rotation_angle_rad(a, a), 0.0);
}

// A rotation about z by 30 deg and a shift is rigid; a shear of 1e-3, a mirror (determinant -1),
// a scale of 1.001, a NaN and a last row that is not (0, 0, 0, 1) are not.
TEST(Pose, IsRigidAcceptsRotationsAndShiftsAndNothingElse) {
  Pose p = Pose::Identity();
  p.rotate(Eigen::AngleAxisd(30.0 * kPi / 180.0, Eigen::Vector3d::UnitZ()));
  p.translation() = Eigen::Vector3d(0.5, -2, 3);
  EXPECT_TRUE(is_rigid(p));
  Pose shear = p;
  shear.matrix()(0, 1) += 1e-3;
  EXPECT_FALSE(is_rigid(shear));
  Pose mirror = p;
  mirror.matrix().col(2) *= -1;
  EXPECT_FALSE(is_rigid(mirror));
  Pose scaled = p;
  scaled.matrix().topLeftCorner<3, 3>() *= 1.001;
  EXPECT_FALSE(is_rigid(scaled));
  Pose nan = p;
  nan.translation().x() = std::nan("");
  EXPECT_FALSE(is_rigid(nan));
  Pose projective = p;
  projective.matrix()(3, 0) = 0.1;
  EXPECT_FALSE(is_rigid(projective));
}
