// A point's colour is the colour image's pixel under its projection through the colour sensor:
// its own intrinsics, its place beside the depth sensor and its lens, checked against
// projections worked by hand.
#include "core/geometry/colour_image.hpp"

#include <gtest/gtest.h>

namespace pbnbv {
namespace {

// A 100 x 80 colour sensor, f = 100 px, principal point at the centre (50, 40); black but for
// the pixels painted.
ColourImage sensor() {
  ColourImage c;
  c.intrinsics = CameraIntrinsics{100, 80, 100, 100, 50, 40};
  c.rgb.assign(100 * 80 * 3, 0);
  return c;
}

void paint(ColourImage& c, int u, int v, Rgb rgb) {
  const std::size_t at = (static_cast<std::size_t>(v) * c.intrinsics.width + static_cast<std::size_t>(u)) * 3;
  for (int k = 0; k < 3; ++k) c.rgb[at + static_cast<std::size_t>(k)] = rgb[static_cast<std::size_t>(k)];
}

TEST(PointColours, APointTakesThePixelItProjectsTo) {
  ColourImage c = sensor();
  paint(c, 70, 40, {255, 0, 0});  // (0.2, 0, 1) m: u = 100 * 0.2 + 50 = 70, v = 40
  paint(c, 50, 30, {0, 255, 0});  // (0, -0.2, 2) m: v = 100 * -0.1 + 40 = 30
  int seen = 0;
  const std::vector<Rgb> got =
      point_colours({{0.2f, 0, 1}, {0, -0.2f, 2}, {0, 0, -1}, {5, 0, 1}}, c, Pose::Identity(), &seen);
  ASSERT_EQ(got.size(), 4u);
  EXPECT_EQ(got[0], (Rgb{255, 0, 0}));
  EXPECT_EQ(got[1], (Rgb{0, 255, 0}));
  EXPECT_EQ(got[2], kNoColour);  // behind the sensor
  EXPECT_EQ(got[3], kNoColour);  // u = 550: outside the image
  EXPECT_EQ(seen, 2);
}

TEST(PointColours, TheColourSensorsPlaceAndTheDepthCamerasPoseAreTakenIntoAccount) {
  // The colour sensor 0.1 m to the right of the depth sensor: (0.2, 0, 1) is at x = 0.1 for it,
  // u = 60 (70 for a colour sensor where the depth sensor is).
  ColourImage c = sensor();
  c.depth_T_colour.translation() = Eigen::Vector3d(0.1, 0, 0);
  paint(c, 60, 40, {0, 0, 255});
  paint(c, 70, 40, {255, 0, 0});
  EXPECT_EQ(point_colours({{0.2f, 0, 1}}, c, Pose::Identity())[0], (Rgb{0, 0, 255}));
  // The depth camera 1 m above the object frame's origin looking down (its z along the object's
  // -z, its x along the object's x): the object point (0.3, 0, 0) is (0.3, 0, 1) for the depth
  // camera and (0.2, 0, 1) for the colour sensor: u = 70.
  Pose object_T_depth = Pose::Identity();
  object_T_depth.linear() = Eigen::Vector3d(1, -1, -1).asDiagonal();
  object_T_depth.translation() = Eigen::Vector3d(0, 0, 1);
  EXPECT_EQ(point_colours({{0.3f, 0, 0}}, c, object_T_depth)[0], (Rgb{255, 0, 0}));
}

TEST(PointColours, AColourLensMovesThePixelAsBrownConradySays) {
  // k1 = -0.25: (0.4, 0, 1) has r^2 = 0.16, x_d = 0.4 (1 - 0.25 * 0.16) = 0.384, u = 88.4 -> 88
  // (a pinhole sensor: 90).
  ColourImage c = sensor();
  c.distortion.k1 = -0.25;
  paint(c, 88, 40, {10, 20, 30});
  paint(c, 90, 40, {200, 200, 200});
  EXPECT_EQ(point_colours({{0.4f, 0, 1}}, c, Pose::Identity())[0], (Rgb{10, 20, 30}));
}

TEST(PointColours, AnImageOfTheWrongSizeIsNamed) {
  ColourImage c = sensor();
  c.rgb.resize(10);
  try {
    c.validate("DEPTH_FRAME 7 colour");
    FAIL() << "a 10-byte image of 100 x 80 passed";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "DEPTH_FRAME 7 colour: 10 bytes of colour for a 100 x 80 image (24000 wanted)");
  }
  c = sensor();
  c.depth_T_colour.linear() *= 2;
  EXPECT_THROW(c.validate("colour"), std::invalid_argument);  // not rigid
}

}  // namespace
}  // namespace pbnbv
