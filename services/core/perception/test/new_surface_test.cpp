// What a view adds to the model (core/perception/new_surface.hpp), on planes whose answer is known
// by hand: a duplicate adds nothing, a plane 1 cm away everything, a half-overlapping one the
// columns beyond the radius; against a k-d tree built beforehand, the same.
#include "core/perception/new_surface.hpp"
#include "core/perception/neighbours.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

using namespace pbnbv;

namespace {

// A square of points on a 2 mm grid, x in [x0, x0 + 0.1], y in [0, 0.1], at height z: 51 x 51.
PointCloud plane(float x0, float z) {
  PointCloud p;
  for (int i = 0; i <= 50; ++i)
    for (int j = 0; j <= 50; ++j) p.emplace_back(x0 + 0.002f * i, 0.002f * j, z);
  return p;
}

}  // namespace

TEST(NewSurface, DuplicateAddsNothingAndAPlaneOneCentimetreAwayAddsEverything) {
  const PointCloud model = plane(0, 0);
  const NewSurface same = new_surface(model, model, 0.005);
  EXPECT_EQ(same.frame_points, 2601);
  EXPECT_EQ(same.model_points, 2601);
  EXPECT_EQ(same.new_points, 0);
  EXPECT_DOUBLE_EQ(same.percent_of_model(), 0.0);
  // 4 mm above: every point within 5 mm of the model.
  EXPECT_EQ(new_surface(plane(0, 0.004f), model, 0.005).new_points, 0);
  const NewSurface above = new_surface(plane(0, 0.01f), model, 0.005);
  EXPECT_EQ(above.new_points, 2601);
  EXPECT_DOUBLE_EQ(above.percent_of_model(), 100.0);
  EXPECT_DOUBLE_EQ(above.percent_of_frame(), 100.0);
}

TEST(NewSurface, HalfOverlappingPlaneCountsTheColumnsBeyondTheRadius) {
  // The frame spans x in [0.05, 0.15], the model x in [0, 0.1]: columns x = 0.106 ... 0.150 lie
  // more than 5 mm beyond the model's edge (0.104 is 4 mm from it): 23 columns of 51 points.
  const NewSurface n = new_surface(plane(0.05f, 0), plane(0, 0), 0.005);
  EXPECT_EQ(n.new_points, 23 * 51);
  EXPECT_NEAR(n.percent_of_model(), 100.0 * 1173 / 2601, 1e-9);  // 45.10 %
  EXPECT_NEAR(n.percent_of_frame(), 100.0 * 23 / 51, 1e-9);
}

// The registration service builds the model's k-d tree while the rig moves: the counts are the
// same as with the tree built on the spot (23 columns of 51 beyond the radius, as above).
TEST(NewSurface, AgainstATreeBuiltBeforehandTheCountsAreTheSame) {
  const NeighbourIndex index(plane(0, 0));
  const NewSurface n = new_surface(plane(0.05f, 0), index, 0.005);
  EXPECT_EQ(n.frame_points, 2601);
  EXPECT_EQ(n.model_points, 2601);
  EXPECT_EQ(n.new_points, 23 * 51);
  EXPECT_EQ(new_surface(plane(0, 0.01f), index, 0.005).new_points, 2601);
  EXPECT_THROW(new_surface(plane(0, 0), index, 0.0), std::invalid_argument);
}

TEST(NewSurface, FirstViewIsAllNew) {
  const NewSurface n = new_surface(plane(0, 0), PointCloud{}, 0.005);
  EXPECT_EQ(n.new_points, 2601);
  EXPECT_EQ(n.model_points, 0);
  EXPECT_DOUBLE_EQ(n.percent_of_model(), 100.0);
}

TEST(NewSurface, ARadiusThatIsNotPositiveIsRefused) {
  EXPECT_THROW(new_surface(plane(0, 0), plane(0, 0), 0.0), std::invalid_argument);
}
