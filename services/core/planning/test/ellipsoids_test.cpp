// Gaussian mixture by BIC, minimum-volume enclosing ellipsoids, quadrics, fit_ellipsoids.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "core/planning/ellipsoids.hpp"
#include "core/base/units.hpp"

using namespace pbnbv;
using Eigen::Matrix3d;
using Eigen::Vector3d;

namespace {

std::vector<Vector3d> gaussian_blob(const Vector3d& mean, const Vector3d& sigma, const Matrix3d& R,
                                    int count, std::mt19937_64& rng) {
  std::normal_distribution<double> nd(0.0, 1.0);
  std::vector<Vector3d> pts;
  for (int i = 0; i < count; ++i) {
    const Vector3d z(nd(rng) * sigma[0], nd(rng) * sigma[1], nd(rng) * sigma[2]);
    pts.push_back(mean + R * z);
  }
  return pts;
}

std::vector<Vector3d> three_blobs(std::vector<Vector3d>* truth) {
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

double log_normal(const Vector3d& x, const Vector3d& mu, const Matrix3d& cov) {
  const Vector3d d = x - mu;
  return -0.5 * (3 * std::log(2 * kPi) + std::log(cov.determinant()) + d.dot(cov.inverse() * d));
}

Matrix3d shape_matrix(const Ellipsoid& e) {
  return e.axes * e.semi_axes.cwiseInverse().cwiseAbs2().asDiagonal() * e.axes.transpose();
}

double inside_value(const Ellipsoid& e, const Vector3d& x) {
  const Vector3d d = x - e.centre;
  return d.dot(shape_matrix(e) * d);
}

std::vector<Vector3d> corners_of(const std::vector<Vector3d>& centres, double voxel) {
  std::vector<Vector3d> out;
  const double h = voxel / 2;
  for (const auto& c : centres)
    for (int m = 0; m < 8; ++m)
      out.push_back(c + Vector3d((m & 1) ? h : -h, (m & 2) ? h : -h, (m & 4) ? h : -h));
  return out;
}

void expect_valid(const Ellipsoid& e) {
  EXPECT_TRUE(e.centre.allFinite());
  EXPECT_TRUE(e.semi_axes.allFinite());
  EXPECT_GT(e.semi_axes.minCoeff(), 0.0);
  EXPECT_NEAR(e.axes.determinant(), 1.0, 1e-9);
  EXPECT_TRUE((e.axes.transpose() * e.axes).isApprox(Matrix3d::Identity(), 1e-9));
}

}  // namespace

TEST(GaussianMixture, BicPicksThreeWellSeparatedGaussiansAndFindsTheirMeans) {
  std::vector<Vector3d> truth;
  const auto pts = three_blobs(&truth);
  const GaussianMixture g = fit_mixture_by_bic(pts, 8, 7, 1e-8);
  ASSERT_EQ(g.weights.size(), 3u);
  ASSERT_EQ(g.labels.size(), pts.size());
  for (const auto& t : truth) {
    double best = 1e9;
    for (const auto& m : g.means) best = std::min(best, (m - t).norm());
    EXPECT_LT(best, 0.01) << t.transpose();
  }
  for (double w : g.weights) EXPECT_NEAR(w, 1.0 / 3, 0.01);
  // Each blob's points share a label, distinct between blobs.
  std::set<int> seen;
  for (int b = 0; b < 3; ++b) {
    const int l = g.labels[b * 300];
    int agree = 0;
    for (int i = 0; i < 300; ++i) agree += g.labels[b * 300 + i] == l;
    EXPECT_GE(agree, 299);
    seen.insert(l);
  }
  EXPECT_EQ(seen.size(), 3u);
}

TEST(GaussianMixture, BicPicksOneForASingleGaussian) {
  std::mt19937_64 rng(3);
  const Matrix3d R = Eigen::AngleAxisd(1.0, Vector3d(0, 1, 1).normalized()).toRotationMatrix();
  const auto pts = gaussian_blob(Vector3d(0.1, 0.2, 0.3), Vector3d(0.05, 0.02, 0.01), R, 600, rng);
  const GaussianMixture g = fit_mixture_by_bic(pts, 6, 1, 1e-8);
  EXPECT_EQ(g.weights.size(), 1u);
  EXPECT_LT((g.means[0] - Vector3d(0.1, 0.2, 0.3)).norm(), 0.005);
}

TEST(GaussianMixture, SameSeedGivesTheIdenticalResult) {
  const auto pts = three_blobs(nullptr);
  const GaussianMixture a = fit_mixture_by_bic(pts, 6, 11, 1e-8);
  const GaussianMixture b = fit_mixture_by_bic(pts, 6, 11, 1e-8);
  ASSERT_EQ(a.weights.size(), b.weights.size());
  EXPECT_EQ(a.bic, b.bic);
  EXPECT_EQ(a.log_likelihood, b.log_likelihood);
  EXPECT_EQ(a.labels, b.labels);
  for (size_t j = 0; j < a.means.size(); ++j) {
    EXPECT_EQ(a.means[j], b.means[j]);
    EXPECT_EQ(a.covariances[j], b.covariances[j]);
    EXPECT_EQ(a.weights[j], b.weights[j]);
  }
}

TEST(GaussianMixture, BicOfOneGaussianIsKLnNMinusTwiceTheLogLikelihood) {
  std::mt19937_64 rng(5);
  const auto pts = gaussian_blob(Vector3d(1, 2, 3), Vector3d(0.1, 0.05, 0.02), Matrix3d::Identity(), 400, rng);
  const double min_var = 1e-6;
  const GaussianMixture g = fit_gaussian_mixture(pts, 1, 1, min_var);
  ASSERT_EQ(g.weights.size(), 1u);
  EXPECT_DOUBLE_EQ(g.weights[0], 1.0);
  // The ML estimate: sample mean and (biased) sample covariance, plus the regularisation.
  Vector3d mean = Vector3d::Zero();
  for (const auto& p : pts) mean += p;
  mean /= pts.size();
  Matrix3d cov = Matrix3d::Zero();
  for (const auto& p : pts) cov += (p - mean) * (p - mean).transpose();
  cov = cov / pts.size() + min_var * Matrix3d::Identity();
  EXPECT_LT((g.means[0] - mean).norm(), 1e-12);
  EXPECT_LT((g.covariances[0] - cov).norm(), 1e-12);
  double lnL = 0;
  for (const auto& p : pts) lnL += log_normal(p, g.means[0], g.covariances[0]);
  const double k = 9;  // (T-1) + 3T + 6T, T = 1
  EXPECT_NEAR(g.log_likelihood, lnL, 1e-8 * std::abs(lnL));
  EXPECT_NEAR(g.bic, k * std::log(400.0) - 2 * lnL, 1e-8 * std::abs(lnL));
}

TEST(GaussianMixture, LogLikelihoodIsTheMixtureLikelihoodAndBicCountsTenTMinusOneParameters) {
  std::vector<Vector3d> truth;
  const auto pts = three_blobs(&truth);
  const GaussianMixture g = fit_gaussian_mixture(pts, 3, 2, 1e-8);
  ASSERT_EQ(g.weights.size(), 3u);
  double lnL = 0;
  for (const auto& p : pts) {
    double s = 0;
    for (int j = 0; j < 3; ++j) s += g.weights[j] * std::exp(log_normal(p, g.means[j], g.covariances[j]));
    lnL += std::log(s);
  }
  EXPECT_NEAR(g.log_likelihood, lnL, 1e-8 * std::abs(lnL));
  EXPECT_NEAR(g.bic, 29 * std::log(900.0) - 2 * lnL, 1e-8 * std::abs(lnL));
  // T is clamped to the number of points.
  const std::vector<Vector3d> two = {Vector3d(0, 0, 0), Vector3d(1, 0, 0)};
  EXPECT_EQ(fit_mixture_by_bic(two, 10, 1, 1e-4).weights.size() <= 2, true);
  EXPECT_EQ(fit_gaussian_mixture(two, 5, 1, 1e-4).weights.size(), 2u);
}

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
