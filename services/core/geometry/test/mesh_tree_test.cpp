// The one mesh AABB tree: distances and segment/ray tests against a box whose answers follow from
// its faces, distances with every kind of hint against a brute force over all the triangles, the
// parallel batch agreeing with single queries, and bad input named (also when it is met inside a
// worker of the parallel loop).
#include "core/geometry/mesh_tree.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
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

constexpr DistanceHints kAllHints[] = {DistanceHints::kNone, DistanceHints::kCgal, DistanceHints::kSurface};

// The nearest point of triangle abc to p, by the regions of the triangle's plane (Ericson,
// Real-Time Collision Detection, 5.1.5): the brute force the tree is checked against.
Vector3d closest_on_triangle(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// The distance from p to the nearest of all the mesh's triangles, one by one.
double brute_force_distance(const TriangleMesh& m, const Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& t : m.triangles) {
    best = std::min(best, (p - closest_on_triangle(p, m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]])).norm());
  }
  return best;
}

TEST(MeshTree, AUnitCubeGivesTheDistancesItsFacesEdgesAndCornersGiveWithEveryHint) {
  // Faces at +-0.5 m.
  const TriangleMesh unit = make_box(Vector3d::Ones());
  const std::vector<std::pair<Vector3d, double>> known = {
      {Vector3d(1, 0, 0), 0.5},                          // off the +x face
      {Vector3d(0.2, -0.1, -2), 1.5},                    // off the -z face
      {Vector3d(0.25, 0.1, 0), 0.25},                    // inside: +x is the nearest face
      {Vector3d(0, 0, 0), 0.5},                          // the centre: every face
      {Vector3d(0.5, 0.2, -0.3), 0.0},                   // on a face
      {Vector3d(0.75, 0.75, 0), std::sqrt(0.125)},       // off the edge x = y = 0.5
      {Vector3d(0.5, 0.5, 0.1), 0.0},                    // on that edge
      {Vector3d(1, 1, 1), std::sqrt(0.75)},              // off the corner (0.5, 0.5, 0.5)
      {Vector3d(-0.5, -0.5, -0.5), 0.0},                 // a corner
      {Vector3d(0.8, -0.9, 0.2), 0.5},                   // off the edge x = 0.5, y = -0.5: 3-4-5
  };
  for (DistanceHints h : kAllHints) {
    const MeshTree tree(unit, h);
    std::vector<Vector3d> pts;
    for (const auto& [p, d] : known) {
      EXPECT_NEAR(tree.distance_m(p), d, 1e-15) << p.transpose() << " hints " << static_cast<int>(h);
      EXPECT_NEAR(brute_force_distance(unit, p), d, 1e-15) << p.transpose();
      pts.push_back(p);
    }
    const std::vector<double> batch = tree.distances_m(pts);
    for (std::size_t i = 0; i < pts.size(); ++i) EXPECT_EQ(batch[i], tree.distance_m(pts[i])) << i;
  }
}

TEST(MeshTree, EveryHintGivesTheBruteForceDistance) {
  // An icosphere of 1,280 triangles, 5,000 points from its centre to three times its radius:
  // each distance is the brute force's over all the triangles, to rounding.
  const TriangleMesh sphere = make_icosphere(0.15, 3);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uni(-0.45, 0.45);
  std::vector<Vector3d> pts(5000);
  for (auto& p : pts) p = Vector3d(uni(rng), uni(rng), uni(rng));
  for (DistanceHints h : kAllHints) {
    const std::vector<double> d = MeshTree(sphere, h).distances_m(pts);
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const double b = brute_force_distance(sphere, pts[i]);
      ASSERT_NEAR(d[i], b, 1e-12 * b + 1e-15) << "point " << i << " hints " << static_cast<int>(h);
    }
  }
}

TEST(MeshTree, TheParallelBatchEqualsSingleQueriesWithEveryHint) {
  const TriangleMesh sphere = make_icosphere(0.15, 3);
  const MeshTree plain(sphere), cgal(sphere, DistanceHints::kCgal), surface(sphere, DistanceHints::kSurface);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uni(-0.3, 0.3);
  std::vector<Vector3d> pts(20000);
  for (auto& p : pts) p = Vector3d(uni(rng), uni(rng), uni(rng));
  const std::vector<double> a = plain.distances_m(pts), b = cgal.distances_m(pts), c = surface.distances_m(pts);
  ASSERT_EQ(a.size(), pts.size());
  for (std::size_t i = 0; i < pts.size(); i += 97) {
    EXPECT_EQ(a[i], plain.distance_m(pts[i])) << i;
    EXPECT_EQ(c[i], surface.distance_m(pts[i])) << i;
  }
  // The same nearest point whatever the hint, so the same bits.
  EXPECT_EQ(a, b);
  EXPECT_EQ(a, c);
  EXPECT_TRUE(plain.distances_m({}).empty());
  EXPECT_TRUE(surface.distances_m({}).empty());
  // distances_to_surface is this tree, built for one batch.
  EXPECT_EQ(distances_to_surface(sphere, pts), a);
}

TEST(MeshTree, SurfaceHintsOnTrianglesOfVaryingSizes) {
  // One large square (two triangles of 0.5 m^2) beside a strip of 200 small ones: the hint
  // points spread over the large triangles too, and the distances are the brute force's.
  TriangleMesh m = make_box(Vector3d(1, 1, 0.01));
  for (int i = 0; i < 100; ++i) {
    const int v = static_cast<int>(m.vertices.size());
    const double x = 0.6 + 0.004 * i;
    m.vertices.insert(m.vertices.end(), {Vector3d(x, 0, 0), Vector3d(x + 0.004, 0, 0), Vector3d(x, 0.004, 0),
                                         Vector3d(x + 0.004, 0.004, 0)});
    m.triangles.emplace_back(v, v + 1, v + 2);
    m.triangles.emplace_back(v + 1, v + 3, v + 2);
  }
  const MeshTree tree(m, DistanceHints::kSurface);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uni(-1.2, 1.2);
  for (int i = 0; i < 2000; ++i) {
    const Vector3d p(uni(rng), uni(rng), uni(rng) / 4);
    const double b = brute_force_distance(m, p);
    ASSERT_NEAR(tree.distance_m(p), b, 1e-12 * b + 1e-15) << p.transpose();
  }
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
  expect_invalid([&] { MeshTree t(broken, DistanceHints::kNone, "coverage"); },
                 {"coverage: ", "mesh triangle 3", "vertex index 8", "[0, 8)"});
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

TEST(MeshTree, ABadPointOfABatchIsNamedWithEveryHint) {
  // 20,000 points: with kCgal several workers of the parallel loop (one per core) each take a
  // share, the one that meets the NaN throws, and the caller gets that error, not
  // std::terminate; the others find it as they put the points in order (morton_order).
  std::vector<Vector3d> pts(20000, Vector3d(0.3, 0, 0));
  pts[17321].z() = std::numeric_limits<double>::quiet_NaN();
  for (DistanceHints h : kAllHints) {
    const MeshTree tree(cube(), h);
    expect_invalid([&] { tree.distances_m(pts); }, {"MeshTree: points[17321] is not finite"});
  }
  expect_invalid([&] { distances_to_surface(cube(), pts); }, {"distances_to_surface: points[17321]"});
}

}  // namespace
}  // namespace pbnbv
