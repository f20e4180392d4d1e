// fit_ellipsoids: voxel clusters -> enclosing ellipsoids, thin clusters, determinism.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "core/planning/ellipsoid_fit.hpp"
#include "core/base/units.hpp"
#include "core/planning/mvee.hpp"
#include "ellipsoid_test_util.hpp"

using namespace pbnbv;
using namespace pbnbv::testing;
using Eigen::Matrix3d;
using Eigen::Vector3d;

TEST(FitEllipsoids, ZeroToThreeVoxels) {
  EllipsoidParams p;
  p.voxel_m = 0.03;
  int T = -1;
  EXPECT_TRUE(fit_ellipsoids({}, EllipsoidClass::kOccupied, p, &T).empty());
  EXPECT_EQ(T, 0);

  const Vector3d c(0.015, 0.045, -0.015);
  auto one = fit_ellipsoids({c}, EllipsoidClass::kFrontier, p, &T);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(T, 1);
  EXPECT_EQ(one[0].cls, EllipsoidClass::kFrontier);
  EXPECT_EQ(one[0].num_points, 1);
  expect_valid(one[0]);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(one[0].semi_axes[i], 0.03 * std::sqrt(3.0) / 2, 1e-4);
  EXPECT_LT((one[0].centre - c).norm(), 1e-6);

  for (int count = 2; count <= 3; ++count) {
    std::vector<Vector3d> vox;
    for (int i = 0; i < count; ++i) vox.push_back(c + Vector3d(0.03 * i, 0.03 * (i / 2), 0));
    auto es = fit_ellipsoids(vox, EllipsoidClass::kOccupied, p, &T);
    ASSERT_EQ(es.size(), 1u) << count;
    EXPECT_EQ(T, 1);
    EXPECT_EQ(es[0].num_points, count);
    expect_valid(es[0]);
    for (const auto& q : corners_of(vox, 0.03)) EXPECT_LE(inside_value(es[0], q), 1 + 1e-3);
    EXPECT_GE(es[0].semi_axes.minCoeff(), 0.015);
  }
}

TEST(FitEllipsoids, OneVoxelThinPlanarClusterGivesAThinValidEllipsoid) {
  const double voxel = 0.03;
  std::vector<Vector3d> vox;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) vox.push_back(Vector3d(0.1 + voxel * i, -0.2 + voxel * j, 0.3));
  EllipsoidParams p;
  p.voxel_m = voxel;
  int T = 0;
  const auto es = fit_ellipsoids(vox, EllipsoidClass::kOccupied, p, &T);
  ASSERT_FALSE(es.empty());
  EXPECT_GE(T, 1);
  int total = 0;
  for (const auto& e : es) {
    expect_valid(e);
    const double smallest = e.semi_axes.minCoeff();
    EXPECT_GT(smallest, voxel / 2);
    EXPECT_LT(smallest, voxel);
    Eigen::Index k;
    e.semi_axes.minCoeff(&k);
    EXPECT_GT(std::abs(e.axes.col(k).z()), 0.999);  // thin along the plane normal
    total += e.num_points;
  }
  EXPECT_EQ(total, 100);
  if (es.size() == 1) {
    EXPECT_NEAR(es[0].semi_axes.minCoeff(), voxel * std::sqrt(3.0) / 2, 1e-3);
  }
  // Every corner of every voxel lies inside (at least) one ellipsoid.
  for (const auto& q : corners_of(vox, voxel)) {
    double best = 1e9;
    for (const auto& e : es) best = std::min(best, inside_value(e, q));
    EXPECT_LE(best, 1 + 1e-3) << q.transpose();
  }
}

TEST(FitEllipsoids, ThreeVoxelBlobsGiveThreeEnclosingEllipsoidsDeterministically) {
  const double voxel = 0.01;
  std::vector<Vector3d> truth;
  const auto pts = three_blobs(&truth);
  std::set<std::tuple<long, long, long>> cells;
  for (const auto& q : pts)
    cells.insert({std::lround(q.x() / voxel), std::lround(q.y() / voxel), std::lround(q.z() / voxel)});
  std::vector<Vector3d> vox;
  for (const auto& [i, j, k] : cells) vox.push_back(voxel * Vector3d(i, j, k));
  EllipsoidParams p;
  p.voxel_m = voxel;
  p.t_max = 8;
  int T = 0;
  const auto es = fit_ellipsoids(vox, EllipsoidClass::kOccupied, p, &T);
  EXPECT_EQ(T, 3);
  ASSERT_EQ(es.size(), 3u);
  int total = 0;
  for (const auto& e : es) {
    expect_valid(e);
    total += e.num_points;
  }
  EXPECT_EQ(total, static_cast<int>(vox.size()));
  for (const auto& q : corners_of(vox, voxel)) {
    double best = 1e9;
    for (const auto& e : es) best = std::min(best, inside_value(e, q));
    EXPECT_LE(best, 1 + 1e-3);
  }
  const auto again = fit_ellipsoids(vox, EllipsoidClass::kOccupied, p);
  ASSERT_EQ(again.size(), es.size());
  for (size_t i = 0; i < es.size(); ++i) {
    EXPECT_EQ(again[i].centre, es[i].centre);
    EXPECT_EQ(again[i].semi_axes, es[i].semi_axes);
  }
}

TEST(FitEllipsoids, MoreThanAThousandVoxelsAreAllLabelledAndEnclosed) {
  // A solid 14 x 14 x 14 block (2744 voxels): the EM runs on a subsample, every voxel is still
  // assigned and enclosed.
  const double voxel = 0.02;
  std::vector<Vector3d> vox;
  for (int i = 0; i < 14; ++i)
    for (int j = 0; j < 14; ++j)
      for (int k = 0; k < 14; ++k) vox.push_back(Vector3d(0.01, 0.01, 0.01) + voxel * Vector3d(i, j, k));
  EllipsoidParams p;
  p.voxel_m = voxel;
  const auto es = fit_ellipsoids(vox, EllipsoidClass::kFrontier, p);
  ASSERT_FALSE(es.empty());
  int total = 0;
  for (const auto& e : es) {
    expect_valid(e);
    EXPECT_EQ(e.cls, EllipsoidClass::kFrontier);
    total += e.num_points;
  }
  EXPECT_EQ(total, static_cast<int>(vox.size()));
  for (const auto& q : corners_of(vox, voxel)) {
    double best = 1e9;
    for (const auto& e : es) best = std::min(best, inside_value(e, q));
    EXPECT_LE(best, 1 + 1e-3);
  }
}

TEST(FitEllipsoids, HullCornersGiveTheEllipsoidOfAllCorners) {
  // An irregular blob of voxels (many interior ones): one cluster's ellipsoid is fitted to the
  // corners that can be hull vertices; it must match the MVEE of all 8 corners of every voxel
  // and enclose them all.
  const double voxel = 0.01;
  std::mt19937_64 rng(17);
  std::normal_distribution<double> nd;
  const Matrix3d R = Eigen::AngleAxisd(0.6, Vector3d(1, 1, -1).normalized()).toRotationMatrix();
  std::set<std::tuple<long, long, long>> cells;
  for (int i = 0; i < 3000; ++i) {
    const Vector3d q = R * Vector3d(0.05 * nd(rng), 0.03 * nd(rng), 0.015 * nd(rng));
    cells.insert({std::lround(q.x() / voxel), std::lround(q.y() / voxel), std::lround(q.z() / voxel)});
  }
  std::vector<Vector3d> vox;
  for (const auto& [i, j, k] : cells) vox.push_back(voxel * Vector3d(i, j, k));
  EllipsoidParams p;
  p.voxel_m = voxel;
  p.t_max = 1;
  const auto es = fit_ellipsoids(vox, EllipsoidClass::kOccupied, p);
  ASSERT_EQ(es.size(), 1u);
  expect_valid(es[0]);
  const auto all = corners_of(vox, voxel);
  const Ellipsoid ref = minimum_volume_ellipsoid(all);
  double worst = 0;
  for (const auto& q : all) worst = std::max(worst, inside_value(es[0], q));
  EXPECT_LE(worst, 1 + 1e-9);
  EXPECT_GT(worst, 0.999);
  Vector3d a = es[0].semi_axes, b = ref.semi_axes;
  std::sort(a.data(), a.data() + 3);
  std::sort(b.data(), b.data() + 3);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(a[i], b[i], 2e-3 * b[i]) << i;
  EXPECT_LT((es[0].centre - ref.centre).norm(), 1e-3 * b[2]);
}

TEST(FitEllipsoids, RepeatedCallsGiveBitIdenticalResults) {
  // The candidate T and the clusters run on two threads; the result must not depend on their
  // timing.
  const double voxel = 0.01;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> nd;
  const std::vector<Vector3d> c = {{0, 0, 0}, {0.2, 0.05, 0}, {0.05, 0.2, 0.1}, {-0.1, 0.1, 0.2}};
  std::set<std::tuple<long, long, long>> cells;
  for (int i = 0; cells.size() < 2000; ++i) {
    const Vector3d q = c[i % 4] + 0.03 * Vector3d(nd(rng), nd(rng), nd(rng));
    cells.insert({std::lround(q.x() / voxel), std::lround(q.y() / voxel), std::lround(q.z() / voxel)});
  }
  std::vector<Vector3d> vox;
  for (const auto& [i, j, k] : cells) vox.push_back(voxel * Vector3d(i, j, k));
  EllipsoidParams p;
  p.voxel_m = voxel;
  int T0 = 0;
  const auto first = fit_ellipsoids(vox, EllipsoidClass::kOccupied, p, &T0);
  EXPECT_EQ(T0, 4);
  for (int run = 0; run < 10; ++run) {
    int T = 0;
    const auto again = fit_ellipsoids(vox, EllipsoidClass::kOccupied, p, &T);
    ASSERT_EQ(T, T0);
    ASSERT_EQ(again.size(), first.size());
    for (size_t i = 0; i < first.size(); ++i) {
      EXPECT_EQ(again[i].num_points, first[i].num_points);
      EXPECT_EQ(again[i].centre, first[i].centre);
      EXPECT_EQ(again[i].axes, first[i].axes);
      EXPECT_EQ(again[i].semi_axes, first[i].semi_axes);
    }
  }
}

// Both classes side by side give exactly what the two fits give one after the other: the
// Occupied ellipsoids first (the three blobs), then the Frontier ones (a one-voxel-thin plate).
TEST(FitEllipsoids, BothClassesSideBySideEqualOneAfterTheOther) {
  const double voxel = 0.01;
  std::vector<Vector3d> truth;
  std::set<std::tuple<long, long, long>> cells;
  for (const auto& q : three_blobs(&truth))
    cells.insert({std::lround(q.x() / voxel), std::lround(q.y() / voxel), std::lround(q.z() / voxel)});
  std::vector<Vector3d> occupied, frontier;
  for (const auto& [i, j, k] : cells) occupied.push_back(voxel * Vector3d(i, j, k));
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 20; ++j) frontier.push_back(voxel * Vector3d(i, j, 40));
  EllipsoidParams p;
  p.voxel_m = voxel;
  int t_occ = 0, t_front = 0, t_occ_seq = 0, t_front_seq = 0;
  const auto both = fit_both_classes(occupied, frontier, p, &t_occ, &t_front);
  auto seq = fit_ellipsoids(occupied, EllipsoidClass::kOccupied, p, &t_occ_seq);
  const auto f = fit_ellipsoids(frontier, EllipsoidClass::kFrontier, p, &t_front_seq);
  seq.insert(seq.end(), f.begin(), f.end());
  EXPECT_EQ(t_occ, 3);
  EXPECT_EQ(t_occ, t_occ_seq);
  EXPECT_EQ(t_front, t_front_seq);
  EXPECT_GE(t_front, 1);
  ASSERT_EQ(both.size(), seq.size());
  for (size_t i = 0; i < both.size(); ++i) {
    EXPECT_EQ(both[i].cls, seq[i].cls);
    EXPECT_EQ(both[i].num_points, seq[i].num_points);
    EXPECT_EQ(both[i].centre, seq[i].centre);
    EXPECT_EQ(both[i].semi_axes, seq[i].semi_axes);
  }
  EXPECT_EQ(both.front().cls, EllipsoidClass::kOccupied);
  EXPECT_EQ(both.back().cls, EllipsoidClass::kFrontier);

  // No Frontier voxel: nothing to aim at, so the Occupied voxels (three blobs, T 3 above) are not
  // fitted either.
  int t_occ_none = -1, t_front_none = -1;
  EXPECT_TRUE(fit_both_classes(occupied, {}, p, &t_occ_none, &t_front_none).empty());
  EXPECT_EQ(t_occ_none, 0);
  EXPECT_EQ(t_front_none, 0);
}
