// Gaussian mixtures by EM, T chosen by BIC: means found, BIC and log-likelihood as defined, determinism.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "core/planning/gmm.hpp"
#include "core/base/units.hpp"
#include "ellipsoid_test_util.hpp"

using namespace pbnbv;
using namespace pbnbv::testing;
using Eigen::Matrix3d;
using Eigen::Vector3d;

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
