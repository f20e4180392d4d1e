// The one mesh AABB tree: distances and segment/ray tests against a box whose answers follow from
// its faces, the parallel batch agreeing with single queries, and bad input named (also when it
// is met inside a worker of the parallel loop).
#include "core/geometry/mesh_tree.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace pbnbv {
namespace {

using Eigen::Vector3d;

// Throws std::invalid_argument whose message contains every needle.
void expect_invalid(const std::function<void()>& fn, const std::vector<std::string>& needles) {
  try {
    fn();
    ADD_FAILURE() << "no exception thrown";
  } catch (const std::invalid_argument& e) {
    for (const std::string& n : needles) {
      EXPECT_NE(std::string(e.what()).find(n), std::string::npos) << "'" << e.what() << "' lacks '" << n << "'";
    }
  }
}

// A 0.2 m cube centred on the origin: faces at +-0.1 m.
const TriangleMesh& cube() {
  static const TriangleMesh m = make_box(Vector3d::Constant(0.2));
  return m;
}

TEST(MeshTree, DistancesToABoxFollowFromItsFaces) {
  const MeshTree tree(cube());
  EXPECT_EQ(tree.num_triangles(), 12u);
  EXPECT_NEAR(tree.distance_m(Vector3d(0.3, 0, 0)), 0.2, 1e-15);                  // off the +x face
  EXPECT_NEAR(tree.distance_m(Vector3d(0, -0.15, 0.02)), 0.05, 1e-15);            // off the -y face
  EXPECT_NEAR(tree.distance_m(Vector3d(0, 0, 0)), 0.1, 1e-15);                    // inside: the surface
  EXPECT_NEAR(tree.distance_m(Vector3d(0.2, 0.2, 0.2)), std::sqrt(3.0) * 0.1, 1e-15);  // off a corner
  EXPECT_NEAR(tree.distance_m(Vector3d(0.13, 0.14, 0)), 0.05, 1e-15);             // off an edge: 3-4-5
  EXPECT_NEAR(tree.distance_m(Vector3d(0.1, 0.05, -0.03)), 0.0, 1e-15);           // on a face
}

TEST(MeshTree, ZeroAreaTrianglesAreLeftOut) {
  TriangleMesh m = cube();
  m.triangles.emplace_back(0, 0, 1);  // two equal corners
  m.vertices.push_back(2 * m.vertices[1] - m.vertices[0]);
  m.triangles.emplace_back(0, 1, static_cast<int>(m.vertices.size()) - 1);  // three collinear
  const MeshTree tree(m);
  EXPECT_EQ(tree.num_triangles(), 12u);
  EXPECT_NEAR(tree.distance_m(Vector3d(0.3, 0, 0)), 0.2, 1e-15);
}

TEST(MeshTree, SegmentsAndRaysHitTheFacesTheyCross) {
  const MeshTree tree(cube());
  EXPECT_FALSE(tree.segment_hits(Vector3d(0.3, 0, 0), Vector3d(0.5, 0, 0)));    // beside it
  EXPECT_TRUE(tree.segment_hits(Vector3d(0.3, 0, 0), Vector3d(0, 0, 0)));       // into it
  EXPECT_TRUE(tree.segment_hits(Vector3d(0.3, 0, 0), Vector3d(-0.3, 0, 0)));    // through it
  EXPECT_TRUE(tree.segment_hits(Vector3d(0.3, 0, 0), Vector3d(0.1, 0, 0)));     // closed: ends on a face
  EXPECT_FALSE(tree.segment_hits(Vector3d(0.3, 0, 0), Vector3d(0.1 + 1e-9, 0, 0)));
  EXPECT_FALSE(tree.segment_hits(Vector3d(-0.3, 0.11, 0), Vector3d(0.3, 0.11, 0)));  // passes 1 cm above +y
  EXPECT_FALSE(tree.segment_hits(Vector3d(0.05, 0, 0), Vector3d(-0.05, 0.02, 0)));   // inside, no face
  EXPECT_TRUE(tree.segment_hits(Vector3d(0.1, 0, 0), Vector3d(0.1, 0, 0)));     // a point on a face
  EXPECT_FALSE(tree.segment_hits(Vector3d(0.2, 0, 0), Vector3d(0.2, 0, 0)));    // a point off it
  EXPECT_TRUE(tree.ray_hits(Vector3d(0.3, 0, 0), Vector3d(-1, 0, 0)));
  EXPECT_FALSE(tree.ray_hits(Vector3d(0.3, 0, 0), Vector3d(1, 0, 0)));          // away from it
  EXPECT_TRUE(tree.ray_hits(Vector3d(0.3, 0.3, 0), Vector3d(-0.2, -0.25, 0.01)));  // meets +x at y = 0.05
  EXPECT_FALSE(tree.ray_hits(Vector3d(0.3, 0.3, 0), Vector3d(-1, -0.2, 0)));  // at x = 0.1, y = 0.26
}

TEST(MeshTree, TheParallelBatchEqualsSingleQueriesWithOrWithoutHints) {
  const TriangleMesh sphere = make_icosphere(0.15, 3);
  const MeshTree plain(sphere), hinted(sphere, true);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uni(-0.3, 0.3);
  std::vector<Vector3d> pts(20000);
  for (auto& p : pts) p = Vector3d(uni(rng), uni(rng), uni(rng));
  const std::vector<double> a = plain.distances_m(pts), b = hinted.distances_m(pts);
  ASSERT_EQ(a.size(), pts.size());
  for (std::size_t i = 0; i < pts.size(); i += 97) EXPECT_EQ(a[i], plain.distance_m(pts[i])) << i;
  EXPECT_EQ(a, b);
  EXPECT_TRUE(plain.distances_m({}).empty());
  // distances_to_surface is this tree, built for one batch.
  EXPECT_EQ(distances_to_surface(sphere, pts), a);
}

TEST(MeshTree, AMovedTreeAnswersTheSame) {
  MeshTree a(cube());
  MeshTree b(std::move(a));
  EXPECT_NEAR(b.distance_m(Vector3d(0.3, 0, 0)), 0.2, 1e-15);
  MeshTree c(make_icosphere(1.0, 0));
  c = std::move(b);
  EXPECT_TRUE(c.segment_hits(Vector3d(0.3, 0, 0), Vector3d(0, 0, 0)));
}

TEST(MeshTree, BadInputIsNamed) {
  TriangleMesh broken = cube();
  broken.triangles[3][2] = 8;
  expect_invalid([&] { MeshTree t(broken, false, "coverage"); }, {"coverage: ", "mesh triangle 3", "vertex index 8", "[0, 8)"});
  TriangleMesh nan = cube();
  nan.vertices[5].x() = std::numeric_limits<double>::quiet_NaN();
  expect_invalid([&] { MeshTree t(nan); }, {"MeshTree: ", "non-finite vertex"});
  TriangleMesh flat;
  flat.vertices = {Vector3d::Zero(), Vector3d::UnitX(), 2 * Vector3d::UnitX()};
  flat.triangles = {Eigen::Vector3i(0, 1, 2)};
  expect_invalid([&] { MeshTree t(flat); }, {"no triangle of non-zero area"});
  expect_invalid([&] { MeshTree t(TriangleMesh{}); }, {"no triangle of non-zero area"});
  const MeshTree tree(cube());
  const double inf = std::numeric_limits<double>::infinity();
  expect_invalid([&] { tree.distance_m(Vector3d(inf, 0, 0)); }, {"not finite"});
  expect_invalid([&] { tree.segment_hits(Vector3d(0, 0, 0), Vector3d(0, inf, 0)); }, {"not finite"});
  expect_invalid([&] { tree.ray_hits(Vector3d(0.3, 0, 0), Vector3d::Zero()); }, {"non-zero direction"});
}

TEST(MeshTree, ABadPointMetInsideAWorkerReachesTheCaller) {
  // 20,000 points: several workers of the parallel loop (one per core) each take a share; the one
  // that meets the NaN throws, and the caller gets that error, not std::terminate.
  const MeshTree tree(cube());
  std::vector<Vector3d> pts(20000, Vector3d(0.3, 0, 0));
  pts[17321].z() = std::numeric_limits<double>::quiet_NaN();
  expect_invalid([&] { tree.distances_m(pts); }, {"MeshTree: points[17321] is not finite"});
  expect_invalid([&] { distances_to_surface(cube(), pts); }, {"distances_to_surface: points[17321]"});
}

}  // namespace
}  // namespace pbnbv
