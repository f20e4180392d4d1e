#pragma once
// The rig tests' fixtures: the rig models loaded once, the 0.3 m cube of the hand-made cases, and
// a view by hand: the arm configuration that puts the camera at `eye` (object
// frame, turntable at 0, the object frame object_z_m above the platter) looking at the object
// frame's origin, of the IK solutions the one quickest to reach from home. A view the arm cannot
// reach fails the test (naming why) and gives home.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/rig/rig.hpp"

namespace pbnbv::testing {

// The rig files of models/, each loaded once per test program.
inline const RigModel& arm_rig() {
  static const RigModel rig = load_rig(default_rig_path(RigKind::kArm));
  return rig;
}
inline const RigModel& free_rig() {
  static const RigModel rig = load_rig(default_rig_path(RigKind::kFree));
  return rig;
}

// A 0.3 m cube resting on the platter: its centre (the object frame) 0.15 m above it, and its
// keep-out box in the object frame.
constexpr double kObjectZ = 0.15;
inline Eigen::AlignedBox3d cube_keepout() {
  return Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-0.15), Eigen::Vector3d::Constant(0.15));
}

inline Vector6d config_seeing_from(const RigModel& rig, const Eigen::Vector3d& eye, double object_z_m) {
  const Pose w_c = object_in_world(rig, 0, object_z_m) * look_at_z_up(eye, Eigen::Vector3d::Zero());
  std::string why;
  const std::vector<Vector6d> sols = inverse_kinematics(rig, w_c * rig.flange_T_camera.inverse(), &why, rig.q_home);
  if (sols.empty()) {
    ADD_FAILURE() << "the arm cannot see from " << eye.transpose() << ": " << why;
    return rig.q_home;
  }
  Vector6d best = sols.front();
  for (const Vector6d& q : sols) {
    if (arm_move_s(rig, rig.q_home, q) < arm_move_s(rig, rig.q_home, best)) best = q;
  }
  return best;
}

}  // namespace pbnbv::testing
