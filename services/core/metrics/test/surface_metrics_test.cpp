// Accuracy, completeness and precision / recall / F-score on geometry whose answers follow by
// hand: a cloud 2 mm above a square, two concentric icospheres, half a cube's surface; and on the
// real bunny, the same figures as CGAL's distance hints (the method before the surface hints).
#include "core/metrics/surface_metrics.hpp"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <tuple>

#include "core/io/mesh_file.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace pbnbv {
namespace {

// A square of side `side` m in the plane z = 0, centred at the origin (two triangles).
TriangleMesh square(double side) {
  const double h = side / 2;
  TriangleMesh m;
  m.vertices = {{-h, -h, 0}, {h, -h, 0}, {h, h, 0}, {-h, h, 0}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

// A grid of points every `step` m over [-h, h]^2 at height z.
PointCloud grid_cloud(double h, double step, double z) {
  PointCloud c;
  const int n = static_cast<int>(std::lround(2 * h / step));
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) c.emplace_back(-h + i * step, -h + j * step, z);
  }
  return c;
}

// The smallest distance from the origin to the plane of a triangle of a mesh around the origin:
// every point of the (convex) mesh lies at least this far from the origin.
double min_plane_distance(const TriangleMesh& m) {
  double h = std::numeric_limits<double>::infinity();
  for (const auto& t : m.triangles) {
    const Eigen::Vector3d a = m.vertices[t[0]], b = m.vertices[t[1]], c = m.vertices[t[2]];
    h = std::min(h, std::abs((b - a).cross(c - a).normalized().dot(a)));
  }
  return h;
}

TEST(DistanceStats, FourValues) {
  const DistanceStats s = distance_stats({4, 1, 3, 2});
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.mean_m, 2.5);
  EXPECT_DOUBLE_EQ(s.median_m, 2.5);                // (2 + 3) / 2
  EXPECT_DOUBLE_EQ(s.rmse_m, std::sqrt(30.0 / 4));  // (1 + 4 + 9 + 16) / 4
  EXPECT_DOUBLE_EQ(s.p95_m, 4);                     // rank ceil(3.8) = 4
  EXPECT_DOUBLE_EQ(s.max_m, 4);
}

TEST(DistanceStats, NearestRankP95) {
  std::vector<double> d;
  for (int i = 20; i >= 1; --i) d.push_back(i);
  const DistanceStats s = distance_stats(d);
  EXPECT_DOUBLE_EQ(s.p95_m, 19);    // rank ceil(0.95 * 20) = 19
  EXPECT_DOUBLE_EQ(s.median_m, 10.5);
  EXPECT_THROW(distance_stats({}), std::invalid_argument);
}

TEST(SurfaceMetrics, CloudTwoMillimetresAboveASquare) {
  // 101 x 101 points every 1 mm, 2 mm above a 10 cm square: every point is 2 mm from it; every
  // reference sample lies under the grid, at most 0.5 mm * sqrt(2) sideways from a point.
  const TriangleMesh ref = square(0.1);
  const PointCloud cloud = grid_cloud(0.05, 0.001, 0.002);
  MetricParams p;
  const SurfaceMetrics m = cloud_metrics(ref, cloud, p);
  EXPECT_EQ(m.model, "cloud");
  EXPECT_EQ(m.accuracy.count, cloud.size());
  for (double v : {m.accuracy.mean_m, m.accuracy.median_m, m.accuracy.rmse_m, m.accuracy.p95_m, m.accuracy.max_m}) {
    EXPECT_NEAR(v, 0.002, 1e-7);
  }
  EXPECT_EQ(m.completeness.count, 10000u);  // 100 cm^2 at 100 samples per cm^2
  EXPECT_GE(m.completeness.mean_m, 0.002 - 1e-7);
  EXPECT_LE(m.completeness.max_m, std::sqrt(0.002 * 0.002 + 2 * 0.0005 * 0.0005) + 1e-7);
  EXPECT_DOUBLE_EQ(m.precision, 1.0);
  EXPECT_DOUBLE_EQ(m.recall, 1.0);
  EXPECT_DOUBLE_EQ(m.f_score, 1.0);
  EXPECT_DOUBLE_EQ(m.threshold_m, 0.005);

  p.threshold_m = 0.001;  // closer than the 2 mm offset: nothing counts either way
  const SurfaceMetrics tight = cloud_metrics(ref, cloud, p);
  EXPECT_DOUBLE_EQ(tight.precision, 0.0);
  EXPECT_DOUBLE_EQ(tight.recall, 0.0);
  EXPECT_DOUBLE_EQ(tight.f_score, 0.0);
}

TEST(SurfaceMetrics, NonFinitePointsAreSkippedAndCounted) {
  PointCloud cloud = grid_cloud(0.05, 0.005, 0.002);
  const std::size_t finite = cloud.size();
  cloud.emplace_back(std::nanf(""), 0.f, 0.f);
  const SurfaceMetrics m = cloud_metrics(square(0.1), cloud);
  EXPECT_EQ(m.skipped_points, 1u);
  EXPECT_EQ(m.accuracy.count, finite);
  EXPECT_NEAR(m.accuracy.max_m, 0.002, 1e-7);
}

TEST(SurfaceMetrics, SphereMeshInsideALargerSphere) {
  // Concentric icospheres of radius 100 and 102 mm. A point of the inner mesh lies between
  // h1 (its faces' smallest distance from the centre) and r1 from the centre, the outer mesh
  // between h2 and r2; so the distance from either surface to the other lies in
  // [h2 - r1, r2 - h1]: 2 mm within the tessellation error, computed from the meshes.
  const double r1 = 0.100, r2 = 0.102;
  const TriangleMesh inner = make_icosphere(r1, 4), outer = make_icosphere(r2, 4);
  const double lo = min_plane_distance(outer) - r1, hi = r2 - min_plane_distance(inner);
  ASSERT_GT(lo, 0.0015);  // the tessellation error is well below the 2 mm
  ASSERT_LT(hi, 0.0025);
  MetricParams sparse;
  sparse.samples_per_cm2 = 20;  // 25,000 samples on each sphere
  const SurfaceMetrics m = mesh_metrics(outer, inner, sparse);
  EXPECT_EQ(m.model, "mesh");
  for (const DistanceStats& s : {m.accuracy, m.completeness}) {
    EXPECT_GT(s.count, 10000u);
    for (double v : {s.mean_m, s.median_m, s.rmse_m, s.p95_m, s.max_m}) {
      EXPECT_GE(v, lo - 1e-9);
      EXPECT_LE(v, hi + 1e-9);
    }
  }
  EXPECT_DOUBLE_EQ(m.f_score, 1.0);  // 5 mm
  MetricParams tight;
  tight.threshold_m = 0.001;
  tight.samples_per_cm2 = 20;
  EXPECT_DOUBLE_EQ(mesh_metrics(outer, inner, tight).f_score, 0.0);
}

TEST(SurfaceMetrics, HalfACubeRecallsItsAreaFraction) {
  // A 10 cm cube; the cloud covers its upper half (top face and the sides above z = 0) with a
  // 0.5 mm grid. Reference samples within t of it: the top, the sides above z = 0 and a band of
  // height t below (minus at most 6 um, the grid's sideways gap): (a^2 + 4 a (a/2 + t)) / 6 a^2.
  const double a = 0.1, h = a / 2, step = 0.0005;
  const TriangleMesh cube = make_box(Eigen::Vector3d(a, a, a));
  PointCloud cloud = grid_cloud(h, step, h);  // top face
  const int n = static_cast<int>(std::lround(a / step));
  for (int i = 0; i <= n; ++i) {
    for (int k = 0; k <= n / 2; ++k) {
      const float u = static_cast<float>(-h + i * step), z = static_cast<float>(k * step);
      cloud.emplace_back(u, -h, z);
      cloud.emplace_back(u, h, z);
      cloud.emplace_back(-h, u, z);
      cloud.emplace_back(h, u, z);
    }
  }
  for (double t : {0.005, 0.001}) {
    MetricParams p;
    p.threshold_m = t;
    const SurfaceMetrics m = cloud_metrics(cube, cloud, p);
    EXPECT_NEAR(m.accuracy.max_m, 0.0, 1e-6);  // every point on the surface
    EXPECT_DOUBLE_EQ(m.precision, 1.0);
    const double expected = (a * a + 4 * a * (h + t)) / (6 * a * a);  // 0.533 at 5 mm, 0.507 at 1 mm
    // 60,000 samples: the binomial spread of the fraction is 0.002; 4 of it.
    EXPECT_NEAR(m.recall, expected, 0.008) << "t = " << t;
    EXPECT_NEAR(m.f_score, 2 * m.recall / (1 + m.recall), 1e-12);
    // The farthest sample: the bottom's centre, h down and h sideways from the sides' z = 0 rows.
    EXPECT_NEAR(m.completeness.max_m, std::sqrt(2.0) * h, 1e-3);
  }
}

// Every figure of `a` equals `b`'s to 1e-12 relative (the same distances, but for a point equally
// near two triangles, whose distance may differ in its last bit).
void expect_same_figures(const SurfaceMetrics& a, const SurfaceMetrics& b) {
  EXPECT_EQ(a.model, b.model);
  EXPECT_EQ(a.skipped_points, b.skipped_points);
  const auto same = [](double x, double y, const char* what) { EXPECT_NEAR(x, y, 1e-12 * std::abs(y)) << what; };
  for (const auto& [s, t, what] : {std::make_tuple(a.accuracy, b.accuracy, "accuracy"),
                                   std::make_tuple(a.completeness, b.completeness, "completeness")}) {
    EXPECT_EQ(s.count, t.count) << what;
    same(s.mean_m, t.mean_m, what);
    same(s.median_m, t.median_m, what);
    same(s.rmse_m, t.rmse_m, what);
    same(s.p95_m, t.p95_m, what);
    same(s.max_m, t.max_m, what);
  }
  EXPECT_EQ(a.precision, b.precision);
  EXPECT_EQ(a.recall, b.recall);
  EXPECT_EQ(a.f_score, b.f_score);
}

TEST(SurfaceMetrics, TheBunnyGivesTheFiguresOfCgalsHints) {
  // The real bunny (3,674 triangles, normalised as the twin renders it: 0.3 m, y up) against a
  // noisy cloud on it with a tenth of its points 1 to 5 cm off, and against itself with its
  // vertices moved up to 1 mm and a third of its triangles left out: the figures with the
  // surface hints (queries in Morton order) are those of CGAL's hints in the order drawn, the
  // method before them.
  TriangleMesh bunny = load_mesh(std::string(PBNBV_DATA_DIR) + "/meshes/bunny.obj");
  normalise_mesh(bunny, 0.3, UpAxis::kY);
  ASSERT_EQ(bunny.triangles.size(), 3674u);
  std::mt19937_64 rng(9);
  std::normal_distribution<double> noise(0.0, 0.0005);
  std::uniform_real_distribution<double> off(0.01, 0.05);
  PointCloud cloud;
  const std::vector<Eigen::Vector3d> on = sample_surface(bunny, 30000, 4);
  for (std::size_t i = 0; i < on.size(); ++i) {
    const Eigen::Vector3d n(noise(rng), noise(rng), noise(rng));
    cloud.push_back((on[i] + (i % 10 == 0 ? off(rng) * n.normalized() : n)).cast<float>());
  }
  TriangleMesh model = bunny;
  std::uniform_real_distribution<double> move(-0.001, 0.001);
  for (auto& v : model.vertices) v += Eigen::Vector3d(move(rng), move(rng), move(rng));
  model.triangles.resize(model.triangles.size() * 2 / 3);
  MetricParams p;
  p.samples_per_cm2 = 20;  // 60,000 samples
  const ReferenceSurface before(bunny, p, DistanceHints::kCgal), now(bunny, p);
  ASSERT_EQ(now.samples().size(), before.samples().size());
  EXPECT_NE(now.samples(), before.samples());  // the same points in another order
  const SurfaceMetrics cloud_now = now.compare_cloud(cloud), mesh_now = now.compare_mesh(model);
  expect_same_figures(cloud_now, before.compare_cloud(cloud));
  expect_same_figures(mesh_now, before.compare_mesh(model));
  // Far enough from a perfect score that a wrong distance would show.
  EXPECT_LT(cloud_now.precision, 0.95);
  EXPECT_LT(mesh_now.recall, 0.9);
}

TEST(SurfaceMetrics, BadInputIsRefusedNamingIt) {
  const TriangleMesh ref = square(0.1);
  try {
    cloud_metrics(ref, PointCloud{});
    FAIL() << "an empty cloud was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no points"), std::string::npos) << e.what();
  }
  EXPECT_THROW(cloud_metrics(ref, PointCloud{Eigen::Vector3f(NAN, 0, 0)}), std::invalid_argument);
  try {
    mesh_metrics(ref, TriangleMesh{});
    FAIL() << "a mesh without faces was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("model mesh"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ReferenceSurface(TriangleMesh{}), std::invalid_argument);
  MetricParams p;
  p.threshold_m = 0;
  EXPECT_THROW(ReferenceSurface(ref, p), std::invalid_argument);
  p = MetricParams{};
  p.samples_per_cm2 = 1e4;  // 1 million samples on 100 cm^2: allowed
  EXPECT_EQ(sample_count(0.01, p.samples_per_cm2), 1000000u);
  EXPECT_THROW(sample_count(10.0, 1e4), std::invalid_argument);  // 1e9 samples
}

}  // namespace
}  // namespace pbnbv
