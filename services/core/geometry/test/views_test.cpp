// Candidate and fixed view sets (views.hpp).
#include "core/geometry/views.hpp"
#include "core/base/units.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numeric>

namespace pbnbv {
namespace {


void expect_looks_at(const Pose& p, const Eigen::Vector3d& centre, double radius) {
  const Eigen::Vector3d to_centre = centre - p.translation();
  EXPECT_NEAR(to_centre.norm(), radius, 1e-9);
  EXPECT_LT((p.linear().col(2) - to_centre.normalized()).norm(), 1e-9);
  EXPECT_LT((p.linear().transpose() * p.linear() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_NEAR(p.linear().determinant(), 1.0, 1e-12);
}

TEST(RingViews, HandComputedFirstView) {
  // Radius 1 at elevation 0, azimuth 0: eye (1, 0, 0) looking along -x; image right = +y,
  // image down = -z.
  const auto v = ring_views(4, 1.0, 0.0, 0.0, Eigen::Vector3d::Zero());
  ASSERT_EQ(v.size(), 4u);
  EXPECT_LT((v[0].translation() - Eigen::Vector3d(1, 0, 0)).norm(), 1e-15);
  EXPECT_LT((v[0].linear().col(2) - Eigen::Vector3d(-1, 0, 0)).norm(), 1e-15);
  EXPECT_LT((v[0].linear().col(0) - Eigen::Vector3d(0, 1, 0)).norm(), 1e-15);
  EXPECT_LT((v[0].linear().col(1) - Eigen::Vector3d(0, 0, -1)).norm(), 1e-15);
  // Second view a quarter turn further: eye (0, 1, 0).
  EXPECT_LT((v[1].translation() - Eigen::Vector3d(0, 1, 0)).norm(), 1e-15);
}

TEST(RingViews, SpacingElevationAndCentre) {
  const Eigen::Vector3d c(0.1, -0.2, 0.3);
  const double r = 0.7, el = 0.35, start = 0.25;
  const auto v = ring_views(12, r, el, start, c);
  ASSERT_EQ(v.size(), 12u);
  for (int k = 0; k < 12; ++k) {
    expect_looks_at(v[k], c, r);
    const Eigen::Vector3d d = v[k].translation() - c;
    EXPECT_NEAR(std::asin(d.z() / r), el, 1e-12);
    const double az = std::atan2(d.y(), d.x());
    EXPECT_NEAR(wrap_angle_rad(az - start - k * kPi / 6), 0.0, 1e-12);
    // Neighbours 30 deg apart: chord = 2 r cos(el) sin(15 deg).
    const Eigen::Vector3d next = v[(k + 1) % 12].translation();
    EXPECT_NEAR((next - v[k].translation()).norm(), 2 * r * std::cos(el) * std::sin(kPi / 12), 1e-12);
    // Image x stays horizontal (z-up hint).
    EXPECT_NEAR(v[k].linear().col(0).z(), 0.0, 1e-12);
  }
  EXPECT_THROW(ring_views(0, r, el, start, c), std::invalid_argument);
}

TEST(SphereBandViews, HemisphereCountsFollowCircumference) {
  const int n = 800, alpha = 24;
  const double r = 0.8598;
  const Eigen::Vector3d c(0, 0, 0.15);
  const auto v = sphere_band_views(n, alpha, r, c, 0, kPi / 2);
  ASSERT_EQ(static_cast<int>(v.size()), n);
  std::map<int, int> per_parallel;
  for (const Pose& p : v) {
    expect_looks_at(p, c, r);
    const double polar = std::acos((p.translation() - c).z() / r);
    const double idx = polar / (kPi / 2 / alpha) - 0.5;  // parallel i at (i + 0.5) * step
    EXPECT_NEAR(idx, std::round(idx), 1e-9);
    ++per_parallel[static_cast<int>(std::round(idx))];
  }
  ASSERT_EQ(static_cast<int>(per_parallel.size()), alpha);
  double wsum = 0;
  for (int i = 0; i < alpha; ++i) wsum += std::sin((i + 0.5) * kPi / 2 / alpha);
  int total = 0;
  for (const auto& [i, count] : per_parallel) {
    const double quota = n * std::sin((i + 0.5) * kPi / 2 / alpha) / wsum;
    EXPECT_LE(std::abs(count - quota), 1.0) << "parallel " << i;
    EXPECT_GE(count, 1);
    total += count;
  }
  EXPECT_EQ(total, n);
  // Parallel 0 (polar 1.875 deg): quota 800 * sin(1.875 deg) / 15.28 = 1.71 -> 1 + the largest
  // remainder -> 2 views; parallel 2: 8.53 -> 9.
  EXPECT_EQ(per_parallel[0], 2);
  EXPECT_EQ(per_parallel[2], 9);
}

TEST(SphereBandViews, EvenAzimuthsOnEachParallel) {
  const auto v = sphere_band_views(40, 4, 1.0, Eigen::Vector3d::Zero(), 0, kPi / 2);
  std::map<long, std::vector<double>> az;
  for (const Pose& p : v) {
    const Eigen::Vector3d d = p.translation();
    az[std::lround(std::acos(d.z()) * 1e6)].push_back(std::atan2(d.y(), d.x()));
  }
  ASSERT_EQ(az.size(), 4u);
  for (auto& [k, a] : az) {
    const int m = static_cast<int>(a.size());
    for (int j = 0; j < m; ++j) {
      EXPECT_NEAR(wrap_angle_rad(a[j] - 2 * kPi * j / m), 0.0, 1e-9);
    }
  }
}

TEST(SphereBandViews, FullSphereIsSymmetric) {
  // Two parallels at 45 and 135 deg of equal circumference: 5 views each.
  const auto v = sphere_band_views(10, 2, 2.0, Eigen::Vector3d(1, 1, 1), 0, kPi);
  ASSERT_EQ(v.size(), 10u);
  int upper = 0;
  for (const Pose& p : v) {
    expect_looks_at(p, Eigen::Vector3d(1, 1, 1), 2.0);
    const double dz = p.translation().z() - 1.0;
    EXPECT_NEAR(std::abs(dz), 2.0 * std::cos(kPi / 4), 1e-12);
    upper += dz > 0;
  }
  EXPECT_EQ(upper, 5);
}

TEST(SphereBandViews, AtLeastOnePerParallelAndBadArguments) {
  // 30 views on 24 parallels of a hemisphere: every parallel gets one, the rest go to the
  // widest ones.
  const auto v = sphere_band_views(30, 24, 1.0, Eigen::Vector3d::Zero(), 0, kPi / 2);
  ASSERT_EQ(v.size(), 30u);
  std::map<long, int> per;
  for (const Pose& p : v) ++per[std::lround(std::acos(p.translation().z()) * 1e6)];
  EXPECT_EQ(per.size(), 24u);
  EXPECT_THROW(sphere_band_views(10, 24, 1.0, Eigen::Vector3d::Zero(), 0, kPi / 2),
               std::invalid_argument);
  EXPECT_THROW(sphere_band_views(100, 0, 1.0, Eigen::Vector3d::Zero(), 0, kPi / 2),
               std::invalid_argument);
  EXPECT_THROW(sphere_band_views(100, 4, -1.0, Eigen::Vector3d::Zero(), 0, kPi / 2),
               std::invalid_argument);
}

// The benchmark's drawn first views: on the sphere (or its upper half) of the given radius,
// deterministic for a seed, uniform (the mean of a few hundred unit directions is near the
// centre: 0 for the sphere, (0, 0, 1/2) for the upper half, whose mean height is 1/2).
TEST(UniformSpherePoints, RadiusHalfSeedAndUniformity) {
  const std::vector<Eigen::Vector3d> full = uniform_sphere_points(400, 0.8, false, 42);
  ASSERT_EQ(full.size(), 400u);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  int below = 0;
  for (const auto& p : full) {
    EXPECT_NEAR(p.norm(), 0.8, 1e-12);
    mean += p / 0.8 / 400.0;
    below += p.z() < 0;
  }
  // Each coordinate of a uniform unit direction has variance 1/3: the mean of 400 has a
  // standard deviation of 0.029, so 0.1 is over 3 of them.
  EXPECT_LT(mean.norm(), 0.1) << mean.transpose();
  EXPECT_GT(below, 150);  // the lower half is drawn too
  EXPECT_LT(below, 250);

  const std::vector<Eigen::Vector3d> half = uniform_sphere_points(400, 0.8, true, 42);
  Eigen::Vector3d half_mean = Eigen::Vector3d::Zero();
  for (const auto& p : half) {
    EXPECT_NEAR(p.norm(), 0.8, 1e-12);
    EXPECT_GE(p.z(), 0.0);
    half_mean += p / 0.8 / 400.0;
  }
  EXPECT_LT(std::hypot(half_mean.x(), half_mean.y()), 0.1) << half_mean.transpose();
  EXPECT_NEAR(half_mean.z(), 0.5, 0.05);  // z uniform on [0, 1]: sd of the mean 0.014

  // The same seed: the same draws; fewer draws: the first ones; another radius: the same directions.
  EXPECT_EQ(uniform_sphere_points(400, 0.8, false, 42), full);
  const std::vector<Eigen::Vector3d> first3 = uniform_sphere_points(3, 0.8, false, 42);
  EXPECT_EQ(first3, std::vector<Eigen::Vector3d>(full.begin(), full.begin() + 3));
  const std::vector<Eigen::Vector3d> far = uniform_sphere_points(3, 1.6, false, 42);
  for (int i = 0; i < 3; ++i) EXPECT_LT((far[i] - 2.0 * full[i]).norm(), 1e-12);
  EXPECT_NE(uniform_sphere_points(3, 0.8, false, 43), first3);  // another seed, other draws
  EXPECT_TRUE(uniform_sphere_points(0, 0.8, false, 42).empty());
  EXPECT_THROW(uniform_sphere_points(-1, 0.8, false, 42), std::invalid_argument);
  EXPECT_THROW(uniform_sphere_points(3, 0.0, false, 42), std::invalid_argument);
  EXPECT_THROW(uniform_sphere_points(3, NAN, false, 42), std::invalid_argument);
}

}  // namespace
}  // namespace pbnbv
