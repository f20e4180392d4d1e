#include "core/geometry/mesh.hpp"
#include "core/base/units.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace pbnbv {
namespace {

namespace fs = std::filesystem;

Eigen::Vector3d normal(const TriangleMesh& m, const Eigen::Vector3i& t) {
  return (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]);
}
Eigen::Vector3d centroid(const TriangleMesh& m, const Eigen::Vector3i& t) {
  return (m.vertices[t[0]] + m.vertices[t[1]] + m.vertices[t[2]]) / 3.0;
}

TEST(Normalise, BoxUpZ) {
  TriangleMesh m = make_box(Eigen::Vector3d(2, 4, 6));
  const MeshNormalisation n = normalise_mesh(m, 0.3, UpAxis::kZ);
  EXPECT_DOUBLE_EQ(n.scale, 0.15);
  EXPECT_EQ(n.up, UpAxis::kZ);
  EXPECT_TRUE(n.up_rotation.isIdentity());
  EXPECT_NEAR((n.extent_m - Eigen::Vector3d(0.3, 0.6, 0.9)).norm(), 0.0, 1e-15);
  EXPECT_EQ(n.extent_m.minCoeff(), 0.3);  // exactly
  EXPECT_NEAR(n.centre_m.norm(), 0.0, 1e-15);
  EXPECT_EQ(n.num_vertices, 8u);
  EXPECT_EQ(n.num_triangles, 12u);
  Eigen::Vector3d lo, hi;
  mesh_bounds(m, lo, hi);
  EXPECT_NEAR((lo + hi).norm(), 0.0, 1e-15);
  EXPECT_NEAR((hi - lo - Eigen::Vector3d(0.3, 0.6, 0.9)).norm(), 0.0, 1e-15);
}

TEST(Normalise, OffsetBoxUpYMapsFileCoordinates) {
  TriangleMesh file = make_box(Eigen::Vector3d(2, 4, 6));
  for (auto& v : file.vertices) v += Eigen::Vector3d(10, -20, 30);
  TriangleMesh m = file;
  const MeshNormalisation n = normalise_mesh(m, 0.3, UpAxis::kY);
  // File y edge (4) becomes z, file z edge (6) becomes y; x (2) is the shortest.
  EXPECT_NEAR((n.extent_m - Eigen::Vector3d(0.3, 0.9, 0.6)).norm(), 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(n.extent_m.minCoeff(), 0.3);
  EXPECT_DOUBLE_EQ(n.scale, 0.15);
  // The rotation takes file +y to +z and file +z to -y.
  EXPECT_TRUE((n.up_rotation * Eigen::Vector3d::UnitY()).isApprox(Eigen::Vector3d::UnitZ()));
  EXPECT_TRUE((n.up_rotation * Eigen::Vector3d::UnitZ()).isApprox(-Eigen::Vector3d::UnitY()));
  EXPECT_NEAR(n.up_rotation.determinant(), 1.0, 1e-15);
  // centre_m is the scaled, rotated bbox centre: 0.15 * (10, -30, -20).
  EXPECT_NEAR((n.centre_m - Eigen::Vector3d(1.5, -4.5, -3.0)).norm(), 0.0, 1e-12);
  // The documented mapping reproduces every vertex.
  for (size_t i = 0; i < m.vertices.size(); ++i) {
    const Eigen::Vector3d mapped = n.scale * (n.up_rotation * file.vertices[i]) - n.centre_m;
    EXPECT_NEAR((mapped - m.vertices[i]).norm(), 0.0, 1e-12);
  }
  Eigen::Vector3d lo, hi;
  mesh_bounds(m, lo, hi);
  EXPECT_NEAR((lo + hi).norm(), 0.0, 1e-12);
  // Winding stays outward (proper rotation).
  for (const auto& t : m.triangles) EXPECT_GT(normal(m, t).dot(centroid(m, t)), 0.0);
}

TEST(Normalise, BoxUpXTurnsFileXUp) {
  TriangleMesh file = make_box(Eigen::Vector3d(2, 4, 6));
  for (auto& v : file.vertices) v += Eigen::Vector3d(10, -20, 30);
  TriangleMesh m = file;
  const MeshNormalisation n = normalise_mesh(m, 0.3, UpAxis::kX);
  EXPECT_EQ(n.up, UpAxis::kX);
  // File x edge (2) becomes z, file z edge (6) becomes x, y (4) stays: 0.15 * (6, 4, 2).
  EXPECT_NEAR((n.extent_m - Eigen::Vector3d(0.9, 0.6, 0.3)).norm(), 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(n.scale, 0.15);
  // The rotation takes file +x to +z, file +z to -x, keeps y.
  EXPECT_TRUE((n.up_rotation * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitZ()));
  EXPECT_TRUE((n.up_rotation * Eigen::Vector3d::UnitZ()).isApprox(-Eigen::Vector3d::UnitX()));
  EXPECT_TRUE((n.up_rotation * Eigen::Vector3d::UnitY()).isApprox(Eigen::Vector3d::UnitY()));
  EXPECT_NEAR(n.up_rotation.determinant(), 1.0, 1e-15);
  // centre_m: the scaled, rotated bbox centre, 0.15 * (-30, -20, 10).
  EXPECT_NEAR((n.centre_m - Eigen::Vector3d(-4.5, -3.0, 1.5)).norm(), 0.0, 1e-12);
  for (size_t i = 0; i < m.vertices.size(); ++i) {
    const Eigen::Vector3d mapped = n.scale * (n.up_rotation * file.vertices[i]) - n.centre_m;
    EXPECT_NEAR((mapped - m.vertices[i]).norm(), 0.0, 1e-12);
  }
  for (const auto& t : m.triangles) EXPECT_GT(normal(m, t).dot(centroid(m, t)), 0.0);  // still outward
}

TEST(Normalise, RejectsBadArguments) {
  TriangleMesh m = make_box(Eigen::Vector3d(1, 1, 1));
  EXPECT_ANY_THROW(normalise_mesh(m, 0.0, UpAxis::kZ));
  EXPECT_ANY_THROW(normalise_mesh(m, -1.0, UpAxis::kZ));
  TriangleMesh empty;
  EXPECT_ANY_THROW(normalise_mesh(empty, 0.3, UpAxis::kZ));
}

// ---- primitives, area --------------------------------------------------------------------
TEST(Primitives, BoxHasOutwardNormalsAndArea) {
  const TriangleMesh b = make_box(Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(b.vertices.size(), 8u);
  ASSERT_EQ(b.triangles.size(), 12u);
  EXPECT_NEAR(mesh_area(b), 2 * (1 * 2 + 2 * 3 + 1 * 3), 1e-12);
  for (const auto& t : b.triangles) EXPECT_GT(normal(b, t).dot(centroid(b, t)), 0.0);
  EXPECT_NEAR(mesh_area(make_box(Eigen::Vector3d(1, 1, 1))), 6.0, 1e-15);
  Eigen::Vector3d lo, hi;
  mesh_bounds(b, lo, hi);
  EXPECT_EQ(lo, Eigen::Vector3d(-0.5, -1, -1.5));
  EXPECT_EQ(hi, Eigen::Vector3d(0.5, 1, 1.5));
}

TEST(Primitives, IcosphereOnSphereOutwardAreaFromBelow) {
  const double r = 0.25;
  const double sphere = 4 * kPi * r * r;
  double previous = 0.0;
  for (int s = 0; s <= 5; ++s) {
    const TriangleMesh m = make_icosphere(r, s);
    EXPECT_EQ(m.triangles.size(), 20u << (2 * s));
    EXPECT_EQ(m.vertices.size(), 10u * (1u << (2 * s)) + 2u);
    for (const auto& v : m.vertices) EXPECT_NEAR(v.norm(), r, 1e-15);
    for (const auto& t : m.triangles) ASSERT_GT(normal(m, t).dot(centroid(m, t)), 0.0);
    const double a = mesh_area(m);
    EXPECT_LT(a, sphere);
    EXPECT_GT(a, previous);
    previous = a;
  }
  EXPECT_NEAR(previous / sphere, 1.0, 2e-3);
}

// ---- sampling ----------------------------------------------------------------------------
TEST(SampleSurface, UniformByAreaOnTheSurfaceDeterministic) {
  const Eigen::Vector3d size(1, 2, 3);
  const TriangleMesh b = make_box(size);
  const size_t n = 20000;
  const auto pts = sample_surface(b, n, 42);
  ASSERT_EQ(pts.size(), n);
  // Face areas: +-x 6, +-y 3, +-z 2 (total 22).
  const double area[3] = {6, 3, 2};
  int count[3][2] = {{0, 0}, {0, 0}, {0, 0}};
  const Eigen::Vector3d h = 0.5 * size;
  for (const auto& p : pts) {
    int on = 0;
    for (int a = 0; a < 3; ++a) {
      if (std::abs(std::abs(p[a]) - h[a]) < 1e-12) {
        ++count[a][p[a] > 0 ? 1 : 0];
        ++on;
      }
      EXPECT_LE(std::abs(p[a]), h[a] + 1e-12);
    }
    EXPECT_GE(on, 1);
  }
  for (int a = 0; a < 3; ++a) {
    for (int s = 0; s < 2; ++s) {
      EXPECT_NEAR(static_cast<double>(count[a][s]) / n, area[a] / 22.0, 0.02) << a << s;
    }
  }
  const auto d = distances_to_surface(b, pts);
  for (double x : d) EXPECT_LT(x, 1e-9);
  EXPECT_EQ(sample_surface(b, n, 42), pts);
  EXPECT_NE(sample_surface(b, n, 43), pts);
  EXPECT_TRUE(sample_surface(b, 0, 1).empty());
}

TEST(SampleSurface, UniformWithinATriangle) {
  // One right triangle split at x = 0.5: the part x < 0.5 holds 3/4 of the area.
  TriangleMesh t;
  t.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  t.triangles = {{0, 1, 2}};
  const auto pts = sample_surface(t, 20000, 7);
  int left = 0;
  for (const auto& p : pts) {
    EXPECT_GE(p.x(), 0.0);
    EXPECT_GE(p.y(), 0.0);
    EXPECT_LE(p.x() + p.y(), 1.0 + 1e-12);
    left += p.x() < 0.5;
  }
  EXPECT_NEAR(left / 20000.0, 0.75, 0.02);
}

// ---- distances ---------------------------------------------------------------------------
TEST(Distances, BoxFaceEdgeCornerRegions) {
  const TriangleMesh b = make_box(Eigen::Vector3d(2, 2, 2));  // [-1, 1]^3
  const std::vector<Eigen::Vector3d> pts = {
      {3, 0, 0},          // face region: 2
      {0.3, -1.5, 0.2},   // face region: 0.5
      {2, 2, 0},          // edge region: sqrt(1 + 1)
      {-1.5, 0.5, 4},     // edge region: sqrt(0.25 + 9)
      {2, 3, 4},          // corner: sqrt(1 + 4 + 9)
      {-2, -2, -2},       // corner: sqrt(3)
      {0, 0, 0.5},        // inside: 0.5 to the +z face
      {1, 0.25, -0.5},    // on the surface
  };
  const std::vector<double> expected = {2.0, 0.5, std::sqrt(2.0), std::sqrt(9.25), std::sqrt(14.0),
                                        std::sqrt(3.0), 0.5, 0.0};
  const auto d = distances_to_surface(b, pts);
  ASSERT_EQ(d.size(), pts.size());
  for (size_t i = 0; i < pts.size(); ++i) EXPECT_NEAR(d[i], expected[i], 1e-12) << i;
  EXPECT_TRUE(distances_to_surface(b, {}).empty());
}

TEST(Distances, IcosphereWithinSagitta) {
  const double r = 0.5;
  const TriangleMesh m = make_icosphere(r, 3);
  // Sagitta: how far inside the sphere a triangle's plane can get.
  double sagitta = 0.0;
  for (const auto& t : m.triangles) {
    const Eigen::Vector3d nrm = normal(m, t).normalized();
    sagitta = std::max(sagitta, r - nrm.dot(m.vertices[t[0]]));
  }
  ASSERT_GT(sagitta, 0.0);
  ASSERT_LT(sagitta, 0.01);
  std::vector<Eigen::Vector3d> pts;
  const auto dirs = sample_surface(make_icosphere(1.0, 1), 500, 3);
  for (size_t i = 0; i < dirs.size(); ++i) {
    const double radius = (i % 2 == 0) ? 1.3 : 0.9;  // outside at 0.8 / 0.4 from the sphere
    pts.push_back(radius * dirs[i].normalized());
  }
  const auto d = distances_to_surface(m, pts);
  for (size_t i = 0; i < pts.size(); ++i) {
    const double nominal = pts[i].norm() - r;
    EXPECT_GE(d[i], nominal - 1e-12);
    EXPECT_LE(d[i], nominal + sagitta + 1e-12);
  }
}

}  // namespace
}  // namespace pbnbv
