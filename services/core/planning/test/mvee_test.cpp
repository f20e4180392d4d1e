// Minimum-volume enclosing ellipsoids and the quadrics of an ellipsoid.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "core/planning/mvee.hpp"
#include "core/base/units.hpp"
#include "ellipsoid_test_util.hpp"

using namespace pbnbv;
using namespace pbnbv::testing;
using Eigen::Matrix3d;
using Eigen::Vector3d;

TEST(Mvee, RecoversAKnownEllipsoidFromSurfacePoints) {
  const Vector3d semi(0.3, 0.2, 0.1), centre(0.5, -0.2, 0.1);
  const Matrix3d R = Eigen::AngleAxisd(0.7, Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  std::mt19937_64 rng(9);
  std::normal_distribution<double> nd;
  std::vector<Vector3d> pts;
  for (int i = 0; i < 2000; ++i) {
    const Vector3d u = Vector3d(nd(rng), nd(rng), nd(rng)).normalized();
    pts.push_back(centre + R * semi.cwiseProduct(u));
  }
  const Ellipsoid e = minimum_volume_ellipsoid(pts);
  expect_valid(e);
  Vector3d got = e.semi_axes;
  std::sort(got.data(), got.data() + 3, std::greater<double>());
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(got[i], semi[i], 0.02 * semi[i]) << i;
  EXPECT_LT((e.centre - centre).norm(), 1e-3);
  // Principal directions match (up to sign) and every point is enclosed.
  for (int i = 0; i < 3; ++i) EXPECT_GT(std::abs(e.axes.col(i).dot(R.col(i))), 0.99) << i;
  double worst = 0;
  for (const auto& p : pts) worst = std::max(worst, inside_value(e, p));
  EXPECT_LE(worst, 1 + 1e-9);
  EXPECT_GT(worst, 0.99);
}

TEST(Mvee, CubeCornersGiveTheCircumscribedSphere) {
  std::vector<Vector3d> pts = corners_of({Vector3d(1, 2, 3)}, 0.2);
  const Ellipsoid e = minimum_volume_ellipsoid(pts);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(e.semi_axes[i], 0.1 * std::sqrt(3.0), 1e-4);
  EXPECT_LT((e.centre - Vector3d(1, 2, 3)).norm(), 1e-6);
}

TEST(Quadric, SurfaceIsZeroCentreNegativeAndDualIsTheInverse) {
  Ellipsoid e;
  e.centre = Vector3d(0.2, -0.1, 0.4);
  e.axes = Eigen::AngleAxisd(0.9, Vector3d(0.3, 1, -0.2).normalized()).toRotationMatrix();
  e.semi_axes = Vector3d(0.25, 0.1, 0.05);
  const Eigen::Matrix4d Q = e.quadric();
  EXPECT_TRUE(Q.isApprox(Q.transpose(), 1e-12));
  std::mt19937_64 rng(1);
  std::normal_distribution<double> nd;
  for (int i = 0; i < 50; ++i) {
    const Vector3d u = Vector3d(nd(rng), nd(rng), nd(rng)).normalized();
    const Vector3d p = e.centre + e.axes * e.semi_axes.cwiseProduct(u);
    EXPECT_NEAR(p.homogeneous().dot(Q * p.homogeneous()), 0.0, 1e-10);
    // Outside positive.
    const Vector3d q = e.centre + 1.1 * e.axes * e.semi_axes.cwiseProduct(u);
    EXPECT_GT(q.homogeneous().dot(Q * q.homogeneous()), 0.0);
  }
  EXPECT_NEAR(e.centre.homogeneous().dot(Q * e.centre.homogeneous()), -1.0, 1e-12);
  Eigen::Matrix4d P = e.dual_quadric() * Q;
  P /= P(3, 3);
  EXPECT_TRUE(P.isApprox(Eigen::Matrix4d::Identity(), 1e-9)) << P;
  EXPECT_TRUE(e.dual_quadric().isApprox(Q.inverse(), 1e-9));
  // The axis-aligned form is the textbook one.
  Ellipsoid s;
  s.semi_axes = Vector3d(1, 2, 4);
  const Eigen::Matrix4d Qs = s.quadric();
  EXPECT_TRUE(Qs.isApprox(Eigen::Vector4d(1, 0.25, 1.0 / 16, -1).asDiagonal().toDenseMatrix()));
}
