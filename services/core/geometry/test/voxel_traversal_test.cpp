// The one voxel traversal (3-D DDA): the cells a ray crosses, in order, with the ray parameter
// where it enters and leaves each, on small grids where every cell can be listed by hand.
#include "core/geometry/voxel_traversal.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <vector>

namespace pbnbv {
namespace {

using Eigen::Vector3d;
using Eigen::Vector3i;

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Visit {
  Vector3i cell;
  double t_in, t_out;
};

// The lattice index of a linear one.
Vector3i index_of(const VoxelLattice& g, int64_t lin) {
  return Vector3i(static_cast<int>(lin % g.dims.x()), static_cast<int>((lin / g.dims.x()) % g.dims.y()),
                  static_cast<int>(lin / (int64_t(g.dims.x()) * g.dims.y())));
}

// Every cell the part [t_min, t_max) of the ray crosses, with its t_in and t_out: the walk, whose
// visitor ends it at t_max (as the ray-casting baseline does).
std::vector<Visit> walk(const VoxelLattice& g, const Vector3d& o, const Vector3d& d, double t_min = 0.0,
                        double t_max = kInf, bool* entered = nullptr) {
  std::vector<Visit> out;
  const bool e = traverse_voxels(g, o, d, t_min, t_max, [&](int64_t lin, double t_in, double t_out) {
    if (t_in >= t_max) return false;
    out.push_back({index_of(g, lin), t_in, t_out});
    return true;
  });
  if (entered) *entered = e;
  return out;
}

std::vector<Vector3i> cells(const std::vector<Visit>& v) {
  std::vector<Vector3i> c;
  for (const Visit& x : v) c.push_back(x.cell);
  return c;
}

const VoxelLattice k543{Vector3i(5, 4, 3), 1.0};

TEST(VoxelTraversal, AlongEachAxisFromOutsideEveryCellOfTheRowOnceWithItsBoundaries) {
  // +x through the row y = 2, z = 1 (centre heights), starting 1 unit before the grid.
  const auto vx = walk(k543, Vector3d(-1, 2.5, 1.5), Vector3d(1, 0, 0));
  ASSERT_EQ(vx.size(), 5u);
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(vx[i].cell, Vector3i(i, 2, 1));
    EXPECT_DOUBLE_EQ(vx[i].t_in, i + 1.0);   // enters cell i at x = i, 1 + i units from the start
    EXPECT_DOUBLE_EQ(vx[i].t_out, i + 2.0);
  }
  // -y through the column x = 3, z = 0: 4 cells, from y = 3 down to 0.
  const auto vy = walk(k543, Vector3d(3.5, 10, 0.5), Vector3d(0, -2, 0));  // |d| = 2: t halves
  ASSERT_EQ(vy.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(vy[i].cell, Vector3i(3, 3 - i, 0));
    EXPECT_DOUBLE_EQ(vy[i].t_in, (10 - 4 + i) / 2.0);
    EXPECT_DOUBLE_EQ(vy[i].t_out, (10 - 4 + i + 1) / 2.0);
  }
  // +z: 3 cells.
  EXPECT_EQ(cells(walk(k543, Vector3d(0.5, 0.5, -4), Vector3d(0, 0, 1))),
            (std::vector<Vector3i>{{0, 0, 0}, {0, 0, 1}, {0, 0, 2}}));
}

TEST(VoxelTraversal, StartingInsideBeginsInTheStartCell) {
  // From the middle of cell (2, 1, 1) towards -x: cells 2, 1, 0; the first is entered at t = 0.
  const auto v = walk(k543, Vector3d(2.5, 1.5, 1.5), Vector3d(-1, 0, 0));
  EXPECT_EQ(cells(v), (std::vector<Vector3i>{{2, 1, 1}, {1, 1, 1}, {0, 1, 1}}));
  EXPECT_DOUBLE_EQ(v[0].t_in, 0.0);
  EXPECT_DOUBLE_EQ(v[0].t_out, 0.5);
  EXPECT_DOUBLE_EQ(v[2].t_out, 2.5);
}

TEST(VoxelTraversal, DiagonalOffTheCornersCrossesTwoCellsPerUnit) {
  // In the plane z = 0.5 of a 4 x 4 x 1 grid, the line y = x + 0.25: it crosses y = 1 at
  // x = 0.75, x = 1 at y = 1.25, y = 2 at x = 1.75, ... and leaves through y = 4 at x = 3.75.
  const VoxelLattice g{Vector3i(4, 4, 1), 1.0};
  const auto v = walk(g, Vector3d(0, 0.25, 0.5), Vector3d(1, 1, 0));
  EXPECT_EQ(cells(v), (std::vector<Vector3i>{{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 2, 0}, {2, 2, 0}, {2, 3, 0}, {3, 3, 0}}));
  const double t_in[] = {0, 0.75, 1, 1.75, 2, 2.75, 3};
  for (std::size_t i = 0; i < v.size(); ++i) EXPECT_DOUBLE_EQ(v[i].t_in, t_in[i]) << i;
  EXPECT_DOUBLE_EQ(v.back().t_out, 3.75);
}

TEST(VoxelTraversal, ThroughEdgesAndCornersItStepsXThenYThenZ) {
  // The 2-D diagonal through the lattice corners (1, 1), (2, 2), (3, 3): at each it meets an x and
  // a y boundary at the same t and steps across x first: 2 * 4 - 1 = 7 cells.
  const VoxelLattice g{Vector3i(4, 4, 1), 1.0};
  EXPECT_EQ(cells(walk(g, Vector3d(0, 0, 0.5), Vector3d(1, 1, 0))),
            (std::vector<Vector3i>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {2, 1, 0}, {2, 2, 0}, {3, 2, 0}, {3, 3, 0}}));
  // The main diagonal of a 3 x 3 x 3 grid through the corners (1,1,1), (2,2,2): x, y, z at each,
  // 3 * (3 - 1) + 1 = 7 cells, the repeated t of a corner appearing as zero-length visits.
  const VoxelLattice c{Vector3i(3, 3, 3), 1.0};
  const auto v = walk(c, Vector3d(0, 0, 0), Vector3d(1, 1, 1));
  EXPECT_EQ(cells(v), (std::vector<Vector3i>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {2, 1, 1}, {2, 2, 1}, {2, 2, 2}}));
  EXPECT_DOUBLE_EQ(v[1].t_in, 1.0);
  EXPECT_DOUBLE_EQ(v[1].t_out, 1.0);  // (1, 0, 0) is only touched at the corner
  EXPECT_DOUBLE_EQ(v[3].t_in, 1.0);
  EXPECT_DOUBLE_EQ(v[3].t_out, 2.0);  // (1, 1, 1) is crossed from corner to corner
}

TEST(VoxelTraversal, CellSizeAndOffsetScaleTheWalk) {
  // The 4 x 4 x 1 off-corner diagonal again with 0.1 m cells: the same cells, t in metres.
  const VoxelLattice g{Vector3i(4, 4, 1), 0.1};
  const auto v = walk(g, Vector3d(0, 0.025, 0.05), Vector3d(1, 1, 0));
  EXPECT_EQ(cells(v), (std::vector<Vector3i>{{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 2, 0}, {2, 2, 0}, {2, 3, 0}, {3, 3, 0}}));
  EXPECT_NEAR(v[1].t_in, 0.075, 1e-15);
  EXPECT_NEAR(v.back().t_out, 0.375, 1e-15);
}

TEST(VoxelTraversal, TheParameterIntervalSetsTheStartAndTheVisitorTheEnd) {
  // +x along a row of 5 cells entered at t = 1: [t_min, t_max) = [2.5, 4.0) covers cells 1 and 2
  // (cell 3 starts at exactly t = 4 and is not visited).
  const auto v = walk(k543, Vector3d(-1, 0.5, 0.5), Vector3d(1, 0, 0), 2.5, 4.0);
  EXPECT_EQ(cells(v), (std::vector<Vector3i>{{1, 0, 0}, {2, 0, 0}}));
  EXPECT_DOUBLE_EQ(v[0].t_in, 2.5);
  // The walk itself goes on to the grid's end: a visitor that never stops sees cells 1 to 4.
  int seen = 0;
  traverse_voxels(k543, Vector3d(-1, 0.5, 0.5), Vector3d(1, 0, 0), 2.5, 4.0, [&](int64_t, double, double) {
    ++seen;
    return true;
  });
  EXPECT_EQ(seen, 4);
  // t_max short of the grid: not entered, nothing visited.
  bool entered = true;
  EXPECT_TRUE(walk(k543, Vector3d(-1, 0.5, 0.5), Vector3d(1, 0, 0), 0.0, 1.0, &entered).empty());
  EXPECT_FALSE(entered);
}

TEST(VoxelTraversal, RaysThatMissEnterNothing) {
  bool entered = true;
  // Parallel to x, above the grid (y = 4.5 > 4).
  EXPECT_TRUE(walk(k543, Vector3d(-1, 4.5, 0.5), Vector3d(1, 0, 0), 0.0, kInf, &entered).empty());
  EXPECT_FALSE(entered);
  // Pointing away from it.
  EXPECT_TRUE(walk(k543, Vector3d(-1, 0.5, 0.5), Vector3d(-1, 0, 0), 0.0, kInf, &entered).empty());
  EXPECT_FALSE(entered);
  // Passing beside it diagonally: y = x + 4.5, already at y = 4.5 > 4 where x = 0, and rising.
  EXPECT_TRUE(walk(k543, Vector3d(-1, 3.5, 0.5), Vector3d(1, 1, 0), 0.0, kInf, &entered).empty());
  EXPECT_FALSE(entered);
}

TEST(VoxelTraversal, TheVisitorEndsTheWalkAndTheLinearIndexIsXFastest) {
  int visits = 0;
  int64_t last = -1;
  const bool entered = traverse_voxels(k543, Vector3d(-1, 2.5, 1.5), Vector3d(1, 0, 0), 0.0, kInf,
                                       [&](int64_t lin, double, double) {
                                         last = lin;
                                         return ++visits < 3;  // stop in the third cell
                                       });
  EXPECT_TRUE(entered);
  EXPECT_EQ(visits, 3);
  EXPECT_EQ(last, 2 + 5 * (2 + 4 * 1));  // cell (2, 2, 1)
}

TEST(VoxelTraversal, TheFirstVisitorHandsTheRestOfTheWalkToTheSecond) {
  // Along +x through a row of 5 cells: the first visitor takes cells 0 and 1 and hands over after
  // cell 1; the second gets cells 2, 3, 4 (to the grid's end) and is never given cell 1 again.
  std::vector<int> first, then;
  const bool entered = traverse_voxels(
      k543, Vector3d(-1, 0.5, 0.5), Vector3d(1, 0, 0), 0.0, kInf,
      [&](int64_t lin, double, double) {
        first.push_back(index_of(k543, lin).x());
        return first.size() == 2 ? VoxelVisit::kHandOver : VoxelVisit::kNext;
      },
      [&](int64_t lin, double t_in, double) {
        then.push_back(index_of(k543, lin).x());
        EXPECT_DOUBLE_EQ(t_in, index_of(k543, lin).x() + 1.0);
        return VoxelVisit::kNext;
      });
  EXPECT_TRUE(entered);
  EXPECT_EQ(first, (std::vector<int>{0, 1}));
  EXPECT_EQ(then, (std::vector<int>{2, 3, 4}));
  // Stopping in the first phase: the second visitor sees nothing.
  then.clear();
  traverse_voxels(
      k543, Vector3d(-1, 0.5, 0.5), Vector3d(1, 0, 0), 0.0, kInf, [](int64_t, double, double) { return VoxelVisit::kStop; },
      [&](int64_t lin, double, double) {
        then.push_back(static_cast<int>(lin));
        return VoxelVisit::kNext;
      });
  EXPECT_TRUE(then.empty());
  // Handing over in the last cell: nothing is left for the second visitor.
  traverse_voxels(
      k543, Vector3d(-1, 0.5, 0.5), Vector3d(1, 0, 0), 5.5, kInf, [](int64_t, double, double) { return VoxelVisit::kHandOver; },
      [&](int64_t lin, double, double) {
        then.push_back(static_cast<int>(lin));
        return VoxelVisit::kNext;
      });
  EXPECT_TRUE(then.empty());
}

TEST(VoxelTraversal, EachCellStartsWhereTheLastEnded) {
  // An oblique ray through a 5 x 4 x 3 grid: the walk is a chain of neighbouring cells (one index
  // step apart), t_in of each is t_out of the one before, and the chain runs from where the ray
  // enters the box to where it leaves it.
  const Vector3d o(-0.7, 0.3, 0.2), d(1.0, 0.55, 0.35);
  const auto v = walk(k543, o, d);
  ASSERT_GE(v.size(), 2u);
  for (std::size_t i = 1; i < v.size(); ++i) {
    EXPECT_EQ((v[i].cell - v[i - 1].cell).cwiseAbs().sum(), 1) << i;
    EXPECT_EQ(v[i].t_in, v[i - 1].t_out) << i;
    EXPECT_LE(v[i].t_in, v[i].t_out) << i;
  }
  EXPECT_DOUBLE_EQ(v.front().t_in, 0.7);                            // x = 0
  EXPECT_DOUBLE_EQ(v.back().t_out, std::min(5.7, (3 - 0.2) / 0.35));  // x = 5 or z = 3, the first
  // 3 - 0.2 = 2.8 over 0.35 is t = 8 (z = 3), beyond x = 5 at t = 5.7: the ray leaves through +x,
  // at y = 0.3 + 5.7 * 0.55 = 3.435 and z = 0.2 + 5.7 * 0.35 = 2.195, inside that face.
  EXPECT_EQ(v.back().cell, Vector3i(4, 3, 2));
}

}  // namespace
}  // namespace pbnbv
