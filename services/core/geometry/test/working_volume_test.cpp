// The working volume of an unknown object: its text form and its bounds in the object frame
// (centred on the volume). The rig file's volume: core/rig/test/rig_working_volume_test.cpp.
#include <gtest/gtest.h>

#include "core/geometry/working_volume.hpp"

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
