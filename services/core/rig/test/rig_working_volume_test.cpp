// The working volume a rig file states, or the one derived from its turntable.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "core/rig/rig.hpp"

using namespace pbnbv;

TEST(WorkingVolume, FromTheRigFileOrDerivedFromTheTurntable) {
  RigModel arm = load_rig(default_rig_path(RigKind::kArm));
  ASSERT_TRUE(arm.working_volume.has_value());
  EXPECT_EQ(working_volume_of(arm).to_text(), "cylinder:0.25,0.5");  // models/rig_arm.xml states it
  EXPECT_DOUBLE_EQ(arm.turntable_radius_m, 0.2);                      // the platter geom
  arm.working_volume.reset();
  EXPECT_EQ(working_volume_of(arm).to_text(), "cylinder:0.25,0.5");  // 1.25 x 0.2 m, twice as tall
  const RigModel free = load_rig(default_rig_path(RigKind::kFree));
  EXPECT_EQ(working_volume_of(free).to_text(), "cylinder:0.25,0.5");
}

// An object turning on the turntable against the rig's fixed parts. models/rig_ur5e.xml: the
// pedestal (0.2 m square, centre 0.70 m from the turntable axis along world -y, 0.50 m tall on the
// table) has its near face 0.60 m from the axis; the arm's base (a cylinder of radius 0.075 m on
// the pedestal's centre) stands 0.50 to 0.586 m above the table, 0.625 m from the axis. The
// platter's top is 0.065 m above the table. A 0.3 m tall object standing on it (its frame 0.15 m
// up) clears the pedestal by 10 mm at radius 0.59 m, and is within the 5 mm margin at 0.597 m; a
// 0.65 m tall one (top 0.715 m above the table) of radius 0.7 m strikes the arm's base as well.
// The KUKA rig's pedestal face is 0.97 m from the axis (0.13 m half-width, centre 1.10 m).
TEST(TurningClearance, AnObjectTurningClearsThePedestalByTheMarginOrStrikesIt) {
  const RigModel ur5e_rig = load_rig(model_file_path("rig_ur5e.xml"));
  ReachabilityChecker ur5e(ur5e_rig);
  // A keep-out box the arm at home reaches into, checked before and after (below).
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-1.5, -1.5, -0.15), Eigen::Vector3d(1.5, 1.5, 1.5));
  const std::vector<std::string> before = ur5e.collisions(ur5e_rig.q_home, 0, box, 0.15);
  EXPECT_FALSE(before.empty());
  EXPECT_TRUE(ur5e.turning_collisions(0.59, -0.15, 0.15, 0.15).empty());
  EXPECT_EQ(ur5e.turning_collisions(0.597, -0.15, 0.15, 0.15), (std::vector<std::string>{"pedestal"}));
  std::vector<std::string> both = ur5e.turning_collisions(0.7, -0.15, 0.5, 0.15);
  std::sort(both.begin(), both.end());
  EXPECT_EQ(both, (std::vector<std::string>{"arm_base", "pedestal"}));
  // Below the arm's base (its bottom 0.5 - 0.065 - 0.15 = 0.285 m above the object frame's origin
  // less the 5 mm margin) only the pedestal.
  EXPECT_EQ(ur5e.turning_collisions(0.7, -0.15, 0.275, 0.15), (std::vector<std::string>{"pedestal"}));
  // The checker's keep-out geom is set anew by each check: one after this gives what it gave before.
  EXPECT_TRUE(ur5e.turning_collisions(0.59, -0.15, 0.15, 0.15).empty());
  EXPECT_EQ(ur5e.collisions(ur5e_rig.q_home, 0, box, 0.15), before);

  ReachabilityChecker kuka(load_rig(default_rig_path(RigKind::kArm)));
  EXPECT_TRUE(kuka.turning_collisions(0.96, -0.15, 0.15, 0.15).empty());
  EXPECT_EQ(kuka.turning_collisions(0.97, -0.15, 0.15, 0.15), (std::vector<std::string>{"pedestal"}));
  ReachabilityChecker free(load_rig(default_rig_path(RigKind::kFree)));
  EXPECT_TRUE(free.turning_collisions(5.0, -1, 1, 0).empty());
}
