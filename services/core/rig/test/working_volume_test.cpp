// The working volume of an unknown object: its text form, its bounds in the object frame (centred
// on the volume), the rig file's volume and the one derived from the turntable.
#include <gtest/gtest.h>

#include "core/rig/rig.hpp"
#include "core/rig/working_volume.hpp"

using namespace pbnbv;

TEST(WorkingVolume, ACylinderAndABoxReadBackAndBoundTheirSpace) {
  const WorkingVolume c = parse_working_volume("cylinder:0.2,0.5");
  EXPECT_EQ(c.shape, WorkingVolume::Shape::kCylinder);
  EXPECT_TRUE(c.bounds().min().isApprox(Eigen::Vector3d(-0.2, -0.2, -0.25)));
  EXPECT_TRUE(c.bounds().max().isApprox(Eigen::Vector3d(0.2, 0.2, 0.25)));
  EXPECT_EQ(c.to_text(), "cylinder:0.2,0.5");
  const WorkingVolume b = parse_working_volume("box:0.4,0.3,0.2");
  EXPECT_EQ(b.shape, WorkingVolume::Shape::kBox);
  EXPECT_TRUE(b.bounds().min().isApprox(Eigen::Vector3d(-0.2, -0.15, -0.1)));
  EXPECT_EQ(parse_working_volume(b.to_text()).to_text(), "box:0.4,0.3,0.2");
}

TEST(WorkingVolume, BadTextIsNamed) {
  auto error_of = [](const std::string& text) {
    try {
      parse_working_volume(text);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error_of("sphere:0.2"), "working volume 'sphere:0.2': expected cylinder:RADIUS,HEIGHT or box:X,Y,Z (m)");
  EXPECT_EQ(error_of("cylinder:0.2"), "working volume 'cylinder:0.2': a cylinder is cylinder:RADIUS,HEIGHT (m)");
  EXPECT_EQ(error_of("box:0.2,0.2"), "working volume 'box:0.2,0.2': a box is box:X,Y,Z (edges, m)");
  EXPECT_EQ(error_of("box:0.2,x,0.2"), "working volume 'box:0.2,x,0.2': 'x' is not a number");
  EXPECT_EQ(error_of("cylinder:0.2,-1"), "working volume 'cylinder:0.2,-1': -1 m is not a size in (0, 3] m");
  EXPECT_EQ(error_of("cylinder:0.2,4"), "working volume 'cylinder:0.2,4': 4 m is not a size in (0, 3] m");
}

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
