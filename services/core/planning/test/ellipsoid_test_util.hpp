#pragma once
// Helpers shared by the Gaussian mixture, MVEE and ellipsoid fit tests: Gaussian blobs, the
// Gaussian log density, the inside test of an ellipsoid, voxel corners, validity of an
// ellipsoid's frame.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <vector>

#include "core/base/units.hpp"
#include "core/planning/ellipsoid.hpp"

namespace pbnbv::testing {

using Eigen::Matrix3d;
using Eigen::Vector3d;

inline std::vector<Vector3d> gaussian_blob(const Vector3d& mean, const Vector3d& sigma, const Matrix3d& R,
                                    int count, std::mt19937_64& rng) {
  std::normal_distribution<double> nd(0.0, 1.0);
  std::vector<Vector3d> pts;
  for (int i = 0; i < count; ++i) {
    const Vector3d z(nd(rng) * sigma[0], nd(rng) * sigma[1], nd(rng) * sigma[2]);
    pts.push_back(mean + R * z);
  }
  return pts;
}

inline std::vector<Vector3d> three_blobs(std::vector<Vector3d>* truth) {
  std::mt19937_64 rng(42);
  const std::vector<Vector3d> centres = {Vector3d(0, 0, 0), Vector3d(0.3, 0, 0),
                                         Vector3d(0.15, 0.3 * std::sqrt(3.0) / 2, 0.05)};
  const Matrix3d R = Eigen::AngleAxisd(0.4, Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  std::vector<Vector3d> pts;
  auto add = [&](const std::vector<Vector3d>& b) { pts.insert(pts.end(), b.begin(), b.end()); };
  add(gaussian_blob(centres[0], Vector3d(0.02, 0.02, 0.02), R, 300, rng));
  add(gaussian_blob(centres[1], Vector3d(0.04, 0.03, 0.02), R, 300, rng));
  add(gaussian_blob(centres[2], Vector3d(0.03, 0.04, 0.025), R.transpose(), 300, rng));
  if (truth) *truth = centres;
  return pts;
}

inline double log_normal(const Vector3d& x, const Vector3d& mu, const Matrix3d& cov) {
  const Vector3d d = x - mu;
  return -0.5 * (3 * std::log(2 * kPi) + std::log(cov.determinant()) + d.dot(cov.inverse() * d));
}

inline Matrix3d shape_matrix(const Ellipsoid& e) {
  return e.axes * e.semi_axes.cwiseInverse().cwiseAbs2().asDiagonal() * e.axes.transpose();
}

inline double inside_value(const Ellipsoid& e, const Vector3d& x) {
  const Vector3d d = x - e.centre;
  return d.dot(shape_matrix(e) * d);
}

inline std::vector<Vector3d> corners_of(const std::vector<Vector3d>& centres, double voxel) {
  std::vector<Vector3d> out;
  const double h = voxel / 2;
  for (const auto& c : centres)
    for (int m = 0; m < 8; ++m)
      out.push_back(c + Vector3d((m & 1) ? h : -h, (m & 2) ? h : -h, (m & 4) ? h : -h));
  return out;
}

inline void expect_valid(const Ellipsoid& e) {
  EXPECT_TRUE(e.centre.allFinite());
  EXPECT_TRUE(e.semi_axes.allFinite());
  EXPECT_GT(e.semi_axes.minCoeff(), 0.0);
  EXPECT_NEAR(e.axes.determinant(), 1.0, 1e-9);
  EXPECT_TRUE((e.axes.transpose() * e.axes).isApprox(Matrix3d::Identity(), 1e-9));
}

}  // namespace pbnbv::testing
