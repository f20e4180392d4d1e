// The Morton order on points whose codes follow by hand: the corners of a cube, a grid of 4 x 4,
// points all alike; and bad input named.
#include "core/geometry/spatial_order.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

namespace pbnbv {
namespace {

using Eigen::Vector3d;

TEST(MortonOrder, TheCornersOfACubeGoXThenYThenZ) {
  // Corner (x, y, z) in {0, 1}^3 has the code x + 2 y + 4 z (the top bit of each index).
  std::vector<Vector3d> corners;
  for (int z = 1; z >= 0; --z) {
    for (int x = 0; x <= 1; ++x) {
      for (int y = 1; y >= 0; --y) corners.emplace_back(x, y, z);
    }
  }
  // Given as (0,1,1) (0,0,1) (1,1,1) (1,0,1) (0,1,0) (0,0,0) (1,1,0) (1,0,0).
  const std::vector<std::uint32_t> order = morton_order(corners, "cube");
  const std::vector<std::uint32_t> expected = {5, 7, 4, 6, 1, 3, 0, 2};
  EXPECT_EQ(order, expected);
  for (std::size_t k = 0; k < order.size(); ++k) {
    const Vector3d& p = corners[order[k]];
    EXPECT_EQ(static_cast<std::size_t>(p.x() + 2 * p.y() + 4 * p.z()), k);
  }
}

TEST(MortonOrder, AGridOfFourByFourVisitsQuadrantsOneAfterAnother) {
  // In the plane z = 0, cells 0..3 along x and y: the Z curve visits the 2 x 2 quadrant at the
  // origin first (x fastest), then the one along +x, then along +y, then the far one.
  std::vector<Vector3d> grid;
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 4; ++x) grid.emplace_back(x, y, 0);  // index 4 y + x
  }
  const std::vector<std::uint32_t> expected = {0, 1, 4, 5, 2, 3, 6, 7, 8, 9, 12, 13, 10, 11, 14, 15};
  EXPECT_EQ(morton_order(grid, "grid"), expected);
}

TEST(MortonOrder, EqualPointsKeepTheirOrderAndNothingIsLeftOut) {
  EXPECT_TRUE(morton_order({}, "none").empty());
  const std::vector<Vector3d> same(5, Vector3d(0.1, -2, 3));
  const std::vector<std::uint32_t> expected = {0, 1, 2, 3, 4};
  EXPECT_EQ(morton_order(same, "same"), expected);
  // 10,000 points spread over a box: a permutation of their indices.
  std::vector<Vector3d> pts;
  for (int i = 0; i < 10000; ++i) pts.emplace_back(std::sin(i), std::cos(3.0 * i), 0.001 * i);
  std::vector<std::uint32_t> order = morton_order(pts, "spread");
  std::sort(order.begin(), order.end());
  std::vector<std::uint32_t> all(pts.size());
  std::iota(all.begin(), all.end(), 0u);
  EXPECT_EQ(order, all);
}

TEST(MortonOrder, ANonFinitePointIsNamed) {
  std::vector<Vector3d> pts(100, Vector3d::Zero());
  pts[42].y() = std::numeric_limits<double>::infinity();
  pts[77].x() = std::numeric_limits<double>::quiet_NaN();
  try {
    morton_order(pts, "queries");
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "queries: points[42] is not finite");
  }
}

}  // namespace
}  // namespace pbnbv
