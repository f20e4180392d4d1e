// The working volume a rig file states, or the one derived from its turntable.
#include <gtest/gtest.h>

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
